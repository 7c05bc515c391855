"""The extension as Blender's own tooling sees it: validate, build, install into a stock bpy.

The install runs in a separate Python that sees only what a stock Blender bundles (bpy,
numpy, OpenImageIO, requests, zstandard, ...), so scikit-image and the other runtime
dependencies must come from the wheels the zip ships. Once installed, the panel is drawn
headlessly and every panel operator runs on a small fog scene.
"""
from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import tomllib
from pathlib import Path

import pytest

from conftest import ROOT

pytestmark = pytest.mark.blender

# What Blender's own Python carries; everything else the extension needs must be a wheel.
STOCK_BLENDER_PACKAGES = ("bpy", "numpy", "numpy.libs", "OpenImageIO", "zstandard", "requests",
                          "certifi", "charset_normalizer", "idna", "urllib3", "Cython", "cython.py")

INSTALL_SCRIPT = r"""
import sys
import bpy
zip_path = sys.argv[-1]
result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                                  enable_on_install=True)
assert result == {"FINISHED"}, result
assert "bl_ext.user_default.xsl_render" in bpy.context.preferences.addons.keys()
assert hasattr(bpy.ops.xsl, "scene_info")
import skimage.filters, skimage.transform, scipy.ndimage, flip_evaluator
for module in (skimage, scipy, flip_evaluator):
    assert "/extensions/" in module.__file__.replace("\\", "/"), module.__file__
print("INSTALLED-AND-REGISTERED")
""" + r"""
# The panel and its operators, from the installed extension.
import importlib
from types import SimpleNamespace
sys.path.insert(0, sys.argv[-2])                      # tests/: the scene and the stub layout
from support.fog_scene import build_fog_scene
from support.ui_stub import draw
EXT = "bl_ext.user_default.xsl_render"
settings_dump = importlib.import_module(EXT + ".addon.scene.state").settings_dump
scene = build_fog_scene(bpy, 32, 18, factory_reset=False)
prefs = bpy.context.preferences.addons[EXT].preferences
prefs.max_spp, prefs.tile_size = 4, 16
assert bpy.ops.xsl.reset_settings() == {"FINISHED"}
assert (scene.xsl_render.max_spp, scene.xsl_render.tile_size) == (4, 16)
context = SimpleNamespace(scene=scene, window_manager=bpy.context.window_manager)
panels = [getattr(bpy.types, name) for name in dir(bpy.types) if name.startswith("RENDER_PT_xsl_render")]
assert len(panels) == 6 and all(panel.poll(context) for panel in panels)
drawn = [entry for panel in panels for entry in draw(bpy, panel, context)]
assert {"xsl.render_budget", "xsl.compute_maps", "xsl.render_selective", "xsl.render_gold", "xsl.compare"} <= {
    entry[1] for entry in drawn if entry[0] == "operator"}
before = settings_dump(scene)
for name in ("compute_maps", "render_selective", "render_gold", "compare"):
    assert getattr(bpy.ops.xsl, name)() == {"FINISHED"}, name
    assert settings_dump(scene) == before, name
for name in ("XSL Z map", "XSL X map", "XSL Snapshot", "XSL S map", "XSL L map", "XSL XS map",
             "XSL XSL map", "XSL Render", "XSL Samples", "XSL Gold", "XSL FLIP heatmap"):
    assert tuple(bpy.data.images[name].size) == (32, 18), name
assert 0.0 < bpy.data.images["XSL FLIP heatmap"]["mean_flip"] < 1.0
scene.render.engine = "BLENDER_EEVEE"
assert not bpy.ops.xsl.render_selective.poll() and not any(panel.poll(context) for panel in panels)
print("PANEL-AND-OPERATORS-OK")
"""


def stock_bpy(tmp_path: Path) -> dict:
    """The environment of a Python that sees only what a stock Blender bundles (run it with
    ``-S -s``), its user folder (where extensions install) in ``tmp_path``."""
    site = Path(sysconfig.get_paths()["purelib"])
    stock = tmp_path / "stock"
    stock.mkdir()
    for name in STOCK_BLENDER_PACKAGES:
        if (site / name).exists():
            (stock / name).symlink_to(site / name)
    return {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(tmp_path),
            "PYTHONPATH": str(stock), "BLENDER_USER_RESOURCES": str(tmp_path / "user")}


def test_manifest_is_complete():
    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    assert manifest["schema_version"] == "1.0.0" and manifest["id"] == "xsl_render"
    assert manifest["blender_version_min"] == "5.0.0"              # what is tested
    # cp311 wheels: Blender 4.2-5.0 (Python 3.11); 5.1 ships a newer Python (exclusive max).
    assert manifest["blender_version_max"] == "5.1.0"
    sys.path.insert(0, str(ROOT / "tools"))
    from build_extension import check_blender_range
    check_blender_range(manifest, manifest["wheels"])
    with pytest.raises(SystemExit, match="5.1 ship"):
        check_blender_range({**manifest, "blender_version_max": "5.2.0"}, manifest["wheels"])
    assert manifest["license"] == ["SPDX:GPL-3.0-or-later"]
    assert manifest["permissions"]["files"]
    excluded = manifest["build"]["paths_exclude_pattern"]
    for pattern in ("/tests/", "/example_blends/", "/.venv/", "__pycache__/"):
        assert pattern in excluded


@pytest.fixture(scope="module")
def built_zips(tmp_path_factory):
    out = tmp_path_factory.mktemp("dist")
    # As the README says: python3 run.py build (tools/build_extension.py in the project's .venv).
    result = subprocess.run([sys.executable, str(ROOT / "run.py"), "build", "--out", str(out)],
                            capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stdout + result.stderr
    return {p.name: p for p in out.glob("*.zip")}


def test_validates_and_builds_one_zip_per_platform(built_zips):
    assert sorted(built_zips) == ["xsl_render-0.1.0-linux_x64.zip", "xsl_render-0.1.0-macos_arm64.zip",
                                  "xsl_render-0.1.0-windows_x64.zip"]


def test_zip_holds_the_extension_and_not_the_repository(built_zips):
    import zipfile

    names = zipfile.ZipFile(built_zips["xsl_render-0.1.0-linux_x64.zip"]).namelist()
    assert "blender_manifest.toml" in names and "__init__.py" in names and "core/camera.py" in names
    assert not [n for n in names if n.startswith(("tests/", "example_blends/", ".venv/", "bench/"))]
    wheels = [n for n in names if n.startswith("wheels/")]
    assert wheels and all("win_amd64" not in n and "macosx" not in n for n in wheels)


def test_linux_zip_installs_into_a_stock_bpy_and_its_panel_works(built_zips, tmp_path):
    script = tmp_path / "install.py"
    script.write_text(INSTALL_SCRIPT)
    env = stock_bpy(tmp_path)
    result = subprocess.run([sys.executable, "-S", "-s", str(script), str(ROOT / "tests"),
                             str(built_zips["xsl_render-0.1.0-linux_x64.zip"])],
                            capture_output=True, text=True, env=env, timeout=600)
    assert "INSTALLED-AND-REGISTERED" in result.stdout, result.stdout[-3000:] + result.stderr[-3000:]
    assert "PANEL-AND-OPERATORS-OK" in result.stdout, result.stdout[-3000:] + result.stderr[-3000:]
    assert "Traceback" not in result.stderr, result.stderr[-3000:]


SHOT_SCRIPT = r"""
import sys
import bpy
result = bpy.ops.extensions.package_install_files(filepath=sys.argv[-1], repo="user_default",
                                                  enable_on_install=False)
assert result == {"FINISHED"}, result
sys.path.insert(0, sys.argv[-3])                      # tests/: the scene
import support.xmap_scenes as xs
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = xs.base_scene(bpy, 32, 18)
scene.render.engine = "CYCLES"
xs.ground_and_props(bpy)
xs.add(bpy, "primitive_cube_add", xs.noise_fog_material(bpy), size=6.0, location=(0.0, 6.0, 1.0))
scene.cycles.samples, scene.cycles.use_denoising = 4, False
scene.render.image_settings.file_format = "OPEN_EXR"
scene.frame_start, scene.frame_end = 1, 4
scene.camera.keyframe_insert("location", frame=1)
scene.camera.location.x += 0.2
scene.camera.keyframe_insert("location", frame=4)
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[-2])
print("SHOT-SAVED")
"""


def test_a_blender_farm_job_renders_a_range_in_a_blender_with_the_extension_from_the_zip(
        built_zips, tmp_path, cli):
    """The farm's plain Blender job (``xsl-render farm``'s default for an animation) run by
    ``openjd`` on this machine: its task is a separate Blender (``support/blender_shim.py``
    on a stock bpy) whose extension was installed from the built zip; the 4 frames render in
    one process, each with Auto Volumes' choice in its header; the .blend is not written."""
    import hashlib

    import yaml
    from test_farm_cli import OPENJD, job_values

    from xsl_render.core.imageio import image_attributes

    env = stock_bpy(tmp_path)
    (tmp_path / "shot.py").write_text(SHOT_SCRIPT)
    blend = tmp_path / "shot.blend"
    made = subprocess.run([sys.executable, "-S", "-s", str(tmp_path / "shot.py"), str(ROOT / "tests"), str(blend),
                           str(built_zips["xsl_render-0.1.0-linux_x64.zip"])],
                          capture_output=True, text=True, env=env, timeout=600)
    assert "SHOT-SAVED" in made.stdout, made.stdout[-3000:] + made.stderr[-3000:]
    digest = hashlib.sha256(blend.read_bytes()).hexdigest()
    blender = tmp_path / "blender"                  # the worker's Blender: the shim on the stock bpy
    blender.write_text("#!/bin/sh\nexec env " + " ".join(f"{k}='{v}'" for k, v in env.items())
                       + f" '{sys.executable}' -S -s '{ROOT / 'tests' / 'support' / 'blender_shim.py'}' \"$@\"\n")
    blender.chmod(0o755)

    bundle = tmp_path / "bundle"
    result = cli("farm", blend, "--bundle", bundle, "--frames-per-task", "4", "--blender", blender)
    assert result.returncode == 0 and "a Blender job, frames 1-4" in result.stdout, result.stderr
    template = yaml.safe_load((bundle / "template.yaml").read_text())
    assert [step["name"] for step in template["steps"]] == ["Render"]
    run = subprocess.run([str(OPENJD), "run", str(bundle / "template.yaml"), "-p", job_values(bundle)],
                         capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-2000:]
    assert run.stdout.count("Auto Volumes: Scene frame") == 4, run.stdout[-4000:]
    assert "Auto Volumes: warning" not in run.stdout + run.stderr
    notes = {image_attributes(bundle / "output" / f"frame_{frame:04d}.exr")["Note"] for frame in range(1, 5)}
    assert len(notes) == 1 and notes.pop().startswith("Auto Volumes: "), notes
    assert hashlib.sha256(blend.read_bytes()).hexdigest() == digest
