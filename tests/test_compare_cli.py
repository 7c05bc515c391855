"""``xsl-render compare``: the table, --json, heatmaps, and one-line errors for bad input."""
from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest

from xsl_render.core.imageio import read_image, write_exr, write_png

# find_spec, not an import: importing torch costs seconds at collection time
HAS_VDP = importlib.util.find_spec("pycvvdp") is not None


def render_like(height: int = 36, width: int = 48, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    rows, cols = np.mgrid[0:height, 0:width].astype(np.float32)
    image = np.stack([cols / width, rows / height, np.full_like(rows, 0.4)], axis=2)
    image[10:20, 10:20] = (3.0, 2.5, 1.5)
    return np.maximum(image + rng.normal(0, 0.03, image.shape).astype(np.float32), 0.0)


@pytest.fixture
def exr_pair(tmp_path):
    reference = render_like()
    test = render_like(seed=1)
    return write_exr(tmp_path / "gold.exr", reference), write_exr(tmp_path / "xs.exr", test)


def test_compare_writes_table_json_and_heatmaps(cli, exr_pair, tmp_path):
    ref, test = exr_pair
    out_json, heatmap, heatmap_dir = tmp_path / "c.json", tmp_path / "flip.png", tmp_path / "maps"
    done = cli("compare", ref, test, "--json", out_json, "--heatmap", heatmap,
               "--heatmap-dir", heatmap_dir, "--no-vdp")
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    lines = done.stdout.splitlines()
    assert lines[0].split()[0] == "metric"
    assert [line.split()[0] for line in lines[1:4]] == ["MSE", "FLIP", "VDP"]
    assert "VDP    skipped: not requested (--no-vdp)" in done.stdout
    assert "HDR-FLIP" in done.stdout

    report = json.loads(out_json.read_text())
    assert report["dynamic_range"] == "HDR" and (report["width"], report["height"]) == (48, 36)
    mse, flip = report["metrics"]["mse"], report["metrics"]["flip"]
    assert 0 < mse["average_error_percent"] < 100 and 0 < mse["error_pixel_percent"] <= 100
    assert flip["average_error_percent"] == pytest.approx(100 * flip["mean_flip"], rel=1e-4)
    assert report["metrics"]["vdp"]["skipped"] == "not requested (--no-vdp)"
    # the table shows the JSON's numbers
    assert f"{mse['average_error_percent']:.4f}" in lines[1]
    assert f"{flip['error_pixel_percent']:.4f}" in lines[2]

    assert sorted(p.name for p in heatmap_dir.iterdir()) == ["flip.png", "mse.png"]
    flip_png = read_image(heatmap)
    assert flip_png.shape == (36, 48, 3)
    np.testing.assert_array_equal(flip_png, read_image(heatmap_dir / "flip.png"))
    assert not list(tmp_path.glob("**/.*partial*"))


def test_compare_of_identical_png_images_is_all_zero(cli, tmp_path):
    image = np.clip(render_like() / 3.0, 0, 1)
    a, b = write_png(tmp_path / "a.png", image), write_png(tmp_path / "b.png", image)
    out_json = tmp_path / "c.json"
    done = cli("compare", a, b, "--json", out_json, *([] if HAS_VDP else ["--no-vdp"]))
    assert done.returncode == 0, done.stderr
    report = json.loads(out_json.read_text())
    assert report["dynamic_range"] == "LDR"
    for name in ("mse", "flip") + (("vdp",) if HAS_VDP else ()):
        assert report["metrics"][name]["average_error_percent"] == 0.0
        assert report["metrics"][name]["error_pixel_percent"] == 0.0
    if HAS_VDP:
        assert report["metrics"]["vdp"]["jod"] == pytest.approx(10.0)


@pytest.mark.skipif(not HAS_VDP, reason="ColorVideoVDP (optional) is not installed")
def test_compare_reports_vdp_heatmap_and_jod(cli, exr_pair, tmp_path):
    ref, test = exr_pair
    out_json, heatmap_dir = tmp_path / "c.json", tmp_path / "maps"
    done = cli("compare", ref, test, "--json", out_json, "--heatmap-dir", heatmap_dir)
    assert done.returncode == 0, done.stderr
    vdp_numbers = json.loads(out_json.read_text())["metrics"]["vdp"]
    assert vdp_numbers["skipped"] is None and vdp_numbers["display"] == "standard_fhd"
    assert 0 < vdp_numbers["average_error_percent"] < 100 and vdp_numbers["jod"] < 10
    assert (heatmap_dir / "vdp.png").is_file()
    assert "JOD" in done.stdout


def _write_bad_inputs(kind: str, tmp_path):
    good = render_like(12, 16)
    ref = write_exr(tmp_path / "ref.exr", good)
    if kind == "missing":
        return ref, tmp_path / "nothere.exr"
    if kind == "size":
        return ref, write_exr(tmp_path / "t.exr", render_like(12, 17))
    if kind == "channels":
        return ref, write_exr(tmp_path / "t.exr", np.concatenate([good, np.ones((12, 16, 1), np.float32)], 2))
    if kind == "kinds":
        return ref, write_png(tmp_path / "t.png", np.clip(good, 0, 1))
    if kind == "suffix":
        (tmp_path / "t.txt").write_text("not an image")
        return ref, tmp_path / "t.txt"
    # NaN / Inf: write_exr refuses them, so write the file with OpenImageIO directly
    import OpenImageIO as oiio

    bad = good.copy()
    bad[3, 4, 0] = np.nan if kind == "nan" else np.inf
    path = tmp_path / "t.exr"
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(16, 12, 3, oiio.FLOAT))
    out.write_image(bad)
    out.close()
    return ref, path


@pytest.mark.parametrize("kind, words", [
    ("missing", "no such image file"), ("size", "differ in size"), ("channels", "channel count"),
    ("nan", "NaN or Inf"), ("inf", "NaN or Inf"), ("kinds", "same kind"),
    ("suffix", "cannot read image"),
])
def test_bad_input_exits_2_with_one_line(cli, tmp_path, kind, words):
    ref, test = _write_bad_inputs(kind, tmp_path)
    out_json = tmp_path / "c.json"
    done = cli("compare", ref, test, "--json", out_json, "--heatmap", tmp_path / "h.png", "--no-vdp")
    assert done.returncode == 2
    assert done.stdout == ""
    assert len(done.stderr.splitlines()) == 1, done.stderr
    assert words in done.stderr and "Traceback" not in done.stderr
    assert not out_json.exists() and not (tmp_path / "h.png").exists()


def test_heatmap_must_be_a_png(cli, exr_pair, tmp_path):
    done = cli("compare", *exr_pair, "--heatmap", tmp_path / "h.exr", "--no-vdp")
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1
    assert ".png" in done.stderr


def _render_fog_scene(bpy, out_dir, sample_counts: tuple[int, ...]) -> dict[int, object]:
    """A plane, a cube of Principled Volume fog and a point light, 64x36, rendered by
    Cycles to float EXR (RGBA) once per sample count, denoiser and adaptive sampling off."""
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 36, 100
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location, camera.rotation_euler = (0.0, -6.0, 1.5), (1.35, 0.0, 0.0)
    bpy.ops.mesh.primitive_plane_add(size=20)
    bpy.ops.mesh.primitive_cube_add(size=2, location=(0.0, 0.0, 1.0))
    fog = bpy.data.materials.new("fog")              # Blender 5 materials have node trees
    nodes = fog.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    volume = nodes.new("ShaderNodeVolumePrincipled")
    volume.inputs["Density"].default_value = 0.3
    fog.node_tree.links.new(volume.outputs[0], nodes["Material Output"].inputs["Volume"])
    bpy.context.object.data.materials.append(fog)
    light = bpy.data.objects.new("light", bpy.data.lights.new("light", "POINT"))
    light.data.energy, light.location = 500.0, (1.0, -1.0, 3.0)
    scene.collection.objects.link(light)
    paths = {}
    for samples in sample_counts:
        scene.cycles.samples, scene.cycles.seed = samples, samples
        scene.render.filepath = str(out_dir / f"fog_{samples}spp.exr")
        bpy.ops.render.render(write_still=True)
        paths[samples] = out_dir / f"fog_{samples}spp.exr"
    return paths


@pytest.mark.blender
@pytest.mark.render
def test_errors_against_a_cycles_reference_fall_with_samples(blender, cli, tmp_path):
    """Cycles is the truth: against a 256-spp render, a 4-spp render of the same fog scene
    must score worse than a 16-spp one on every metric, and the gold one against itself 0."""
    paths = _render_fog_scene(blender, tmp_path, (4, 16, 256))
    assert read_image(paths[256]).shape == (36, 64, 4)          # Cycles writes RGBA
    reports = {}
    for samples in (4, 16, 256):
        out_json = tmp_path / f"c{samples}.json"
        with_vdp = HAS_VDP and samples != 256      # VDP of identical images: test_metrics
        done = cli("compare", paths[256], paths[samples], "--json", out_json,
                   *([] if with_vdp else ["--no-vdp"]))
        assert done.returncode == 0, done.stderr
        reports[samples] = json.loads(out_json.read_text())["metrics"]
    for name in ("mse", "flip"):
        for number in ("average_error_percent", "error_pixel_percent"):
            assert reports[256][name][number] == 0.0
    for name in ("mse", "flip") + (("vdp",) if HAS_VDP else ()):
        assert reports[4][name]["average_error_percent"] > reports[16][name]["average_error_percent"] > 0
    assert reports[4]["flip"]["mean_flip"] > reports[16]["flip"]["mean_flip"]
    if HAS_VDP:
        assert reports[4]["vdp"]["jod"] < reports[16]["vdp"]["jod"] < 10.0


def _compare_json(capfd, tmp_path, *images, extra=()):
    """``xsl-render compare`` in this process (the console script is tested above)."""
    from xsl_render.operators.cli import main

    out = tmp_path / "c.json"
    capfd.readouterr()
    assert main(["compare", *map(str, images), "--json", str(out), "--no-vdp", *extra]) == 0
    printed = capfd.readouterr()
    assert printed.err == "" and "nan" not in printed.out.lower()
    return json.loads(out.read_text())


def test_a_black_hdr_reference_and_a_huge_exposure(cli, capfd, tmp_path):
    """Issue 15, point 1: FLIP's own exposure range fails on a black reference and used to end
    the process (exit 255, nothing said); --exposure 1000 used to print MSE nan."""
    black = write_exr(tmp_path / "black.exr", np.zeros((36, 64, 4), np.float32))
    grey = write_exr(tmp_path / "grey.exr", np.full((36, 64, 4), 0.18, np.float32))
    done = cli("compare", black, black, "--json", tmp_path / "same.json", "--no-vdp")    # the whole process
    assert (done.returncode, done.stderr) == (0, ""), done.stderr
    same = json.loads((tmp_path / "same.json").read_text())["metrics"]
    assert same["flip"]["mean_flip"] == 0.0 and same["mse"]["mse"] == 0.0
    lit = _compare_json(capfd, tmp_path, black, grey)["metrics"]
    assert lit["flip"]["mean_flip"] > 0.5 and lit["flip"]["error_pixel_percent"] == 100.0
    nearly = write_exr(tmp_path / "nearly.exr", np.full((36, 64, 4), 1e-30, np.float32))
    assert _compare_json(capfd, tmp_path, nearly, black)["metrics"]["flip"]["mean_flip"] == 0.0
    bright = _compare_json(capfd, tmp_path, grey, black, extra=("--exposure", "64"))["metrics"]
    assert bright["mse"]["mse"] == pytest.approx(1.0)         # white against black, not NaN
    # --exposure 1000 is refused while parsing (tests/test_fuzz_cli.py, compare-exposure-huge).


def test_the_display_transform_never_makes_nan():
    from xsl_render.core.tonemap import standard_view

    image = np.array([[[0.0, 0.5, 1e30]]], np.float32)
    for exposure in (-1e6, -1000.0, 0.0, 64.0, 1000.0, 1e6):
        with np.errstate(all="raise"):
            view = standard_view(image, exposure)
        assert np.isfinite(view).all() and view.min() >= 0.0 and view.max() <= 1.0


def test_hdr_or_ldr_is_read_from_the_pixels_not_the_name(cli, capfd, tmp_path):
    """Issue 15, point 12: a float TIFF is a linear render, a PNG named .exr is display values."""
    import OpenImageIO as oiio

    rng = np.random.default_rng(3)
    values = rng.random((24, 32, 3)).astype(np.float32)
    write_png(tmp_path / "a.png", values)
    (tmp_path / "a_named.exr").write_bytes((tmp_path / "a.png").read_bytes())
    assert _compare_json(capfd, tmp_path, tmp_path / "a_named.exr", tmp_path / "a.png")["dynamic_range"] == "LDR"
    for name, data in (("f.tif", values), ("g.tif", values * 2.0)):
        out = oiio.ImageOutput.create(str(tmp_path / name))
        out.open(str(tmp_path / name), oiio.ImageSpec(32, 24, 3, oiio.FLOAT))
        out.write_image(data)
        out.close()
    report = _compare_json(capfd, tmp_path, tmp_path / "f.tif", tmp_path / "g.tif")
    assert report["dynamic_range"] == "HDR" and report["metrics"]["flip"]["mode"] == "HDR-FLIP"
    write_exr(tmp_path / "f.exr", values)
    assert _compare_json(capfd, tmp_path, tmp_path / "f.exr", tmp_path / "f.tif")["metrics"]["flip"]["mean_flip"] == 0
    done = cli("compare", tmp_path / "f.tif", tmp_path / "a.png", "--no-vdp")
    assert done.returncode == 2 and "same kind" in done.stderr


@pytest.mark.parametrize("kind", ["hdr", "ldr"])
def test_1x1_images_compare_like_any_other(capfd, tmp_path, kind):
    """Issue 15, point 12: two different 1x1 images differ, the same one does not."""
    write = write_exr if kind == "hdr" else write_png
    suffix = ".exr" if kind == "hdr" else ".png"
    a = write(tmp_path / f"a{suffix}", np.array([[[0.2, 0.3, 0.4]]], np.float32))
    b = write(tmp_path / f"b{suffix}", np.array([[[0.9, 0.1, 0.4]]], np.float32))
    different = _compare_json(capfd, tmp_path, a, b)["metrics"]
    assert different["flip"]["mean_flip"] > 0.1 and different["mse"]["mse"] > 0.01
    assert _compare_json(capfd, tmp_path, a, a)["metrics"]["flip"]["mean_flip"] == 0.0
