"""The converged reference: its defaults and key (core.validation.reference), the cache (a hit
renders nothing, any changed input misses, entries are whole or absent), the entry shipped
for the demo, and ``xsl-render reference`` on the command line."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import EXAMPLES, xsl_render_cli
from support.fog_scene import saved_fog_scene
from test_cli_info import one_line_error

from xsl_render.core.errors import Cancelled, InputError
from xsl_render.core.files import file_sha256
from xsl_render.core.imageio import image_attributes, read_image, write_exr
from xsl_render.core.validation.reference import (MIN_REFERENCE_SPP, REFERENCE_SEED, ReferenceInputs,
                                                  cache_root, check_contestant_seeds,
                                                  default_reference_spp, find_reference,
                                                  read_reference, shipped_folders, write_reference, ReferenceRun)

W, H = 32, 18
SHIPPED = EXAMPLES / "references"
INPUTS = ReferenceInputs("ab" * 32, "Scene", 1, (W, H), 64, REFERENCE_SEED, "5.0.1", "oidn-1")


# -- plain data -------------------------------------------------------------------------
@pytest.mark.parametrize("ceiling, spp", [(1, 1024), (16, 1024), (64, 1024), (65, 1040), (256, 4096)])
def test_default_samples_are_16x_the_ceiling_and_at_least_1024(ceiling, spp):
    assert default_reference_spp(ceiling) == spp == max(MIN_REFERENCE_SPP, 16 * ceiling)


@pytest.mark.parametrize("field, value", [
    ("blend_sha256", "cd" * 32), ("scene", "Other"), ("frame", 2), ("resolution", (W, H + 1)),
    ("spp", 65), ("seed", 8), ("blender", "5.1.0"), ("denoise", "oidn-2"),
])
def test_every_input_changes_the_key(field, value):
    changed = ReferenceInputs(**{**INPUTS.__dict__, field: value})
    assert changed.key != INPUTS.key
    assert ReferenceInputs.from_dict(json.loads(json.dumps(INPUTS.to_dict()))).key == INPUTS.key


@pytest.mark.parametrize("environ, expected", [
    ({"XSL_RENDER_CACHE": "/x/cache", "XDG_CACHE_HOME": "/y"}, Path("/x/cache")),
    ({"XDG_CACHE_HOME": "/y"}, Path("/y/xsl_render")),
    ({}, Path.home() / ".cache" / "xsl_render"),
])
def test_cache_root(environ, expected):
    assert cache_root(environ) == expected


def test_a_contestant_never_renders_with_the_reference_seed():
    check_contestant_seeds([0, 1, 2], REFERENCE_SEED)
    check_contestant_seeds([7], None)                  # a reference of unknown seed
    with pytest.raises(InputError, match="contestant seed 7 is the converged reference's seed"):
        check_contestant_seeds(range(8), REFERENCE_SEED)


def test_an_entry_is_a_hit_only_when_whole(tmp_path):
    environ = {"XSL_RENDER_CACHE": str(tmp_path)}
    folder = tmp_path / "references"
    image = np.full((H, W, 4), 0.5, np.float32)
    entry = write_reference(folder, INPUTS, image, ReferenceRun({"wall_s": 1.0}, 2.0))
    assert sorted(p.name for p in folder.iterdir()) == [f"{INPUTS.key}.exr", f"{INPUTS.key}.json"]
    found = find_reference(INPUTS.key, environ)
    assert found.source == "cache" and found.path == entry.path
    assert np.array_equal(read_image(found.path), image)
    assert image_attributes(found.path)["xsl_render:reference_seed"] == REFERENCE_SEED
    given = read_reference(found.path, (W, H))
    assert (given.seed, given.spp, given.key) == (REFERENCE_SEED, 64, INPUTS.key)
    with pytest.raises(InputError, match=f"is {W}x{H}, the runs render at 64x36"):
        read_reference(found.path, (64, 36))
    # An image without its record (a render killed before the record) is no entry...
    (folder / f"{INPUTS.key}.json").unlink()
    assert find_reference(INPUTS.key, environ) is None
    # ... nor a record whose image is gone, nor one made for other inputs.
    write_reference(folder, INPUTS, image, ReferenceRun({}))
    entry.path.unlink()
    assert find_reference(INPUTS.key, environ) is None
    other = ReferenceInputs(**{**INPUTS.__dict__, "spp": 128})
    write_reference(folder, other, image, ReferenceRun({}))
    (folder / f"{other.key}.json").rename(folder / f"{INPUTS.key}.json")
    write_exr(folder / f"{INPUTS.key}.exr", image)
    assert find_reference(INPUTS.key, environ) is None
    assert not list(folder.glob(".*partial*"))


# -- the entry shipped for the demo ------------------------------------------------------
def shipped_entry() -> tuple[Path, dict]:
    records = sorted(SHIPPED.glob("*.json"))
    assert len(records) == 1, records
    return records[0], json.loads(records[0].read_text())


def test_the_shipped_road_reference_matches_the_committed_scene_and_denoiser():
    """Changing road.blend or the denoiser without tools/regenerate_reference.py fails here."""
    from xsl_render.addon.cycles.denoise import DENOISE_VERSION

    path, record = shipped_entry()
    inputs = ReferenceInputs.from_dict(record["inputs"])
    assert record["file"] == "road.blend"
    assert inputs.blend_sha256 == file_sha256(EXAMPLES / "road.blend")
    assert inputs.denoise == DENOISE_VERSION
    assert (inputs.resolution, inputs.spp, inputs.seed) == ((512, 288), 1024, REFERENCE_SEED)
    assert inputs.key == record["input_hash"] == path.stem
    exr = path.with_suffix(".exr")
    assert exr.stat().st_size < 3_000_000
    image = read_image(exr)
    assert image.shape == (288, 512, 4) and image.dtype == np.float32 and np.isfinite(image).all()
    assert SHIPPED in shipped_folders()


@pytest.mark.blender
def test_the_code_computes_the_shipped_key_for_road():
    from xsl_render.addon.scene.blend_session import open_blend
    from xsl_render.addon.validation.reference import reference_inputs

    path, _ = shipped_entry()
    scene = open_blend(EXAMPLES / "road.blend")
    inputs = reference_inputs(scene, EXAMPLES / "road.blend", max_spp=64)      # the demo's
    assert inputs.key == path.stem
    assert find_reference(inputs.key).source == "shipped"


# -- rendering and the cache -------------------------------------------------------------
@pytest.fixture(scope="module")
def fog_blend(tmp_path_factory):
    return saved_fog_scene(tmp_path_factory.mktemp("scene"), W, H)


@pytest.mark.blender
@pytest.mark.render
def test_a_hit_renders_nothing_and_a_changed_input_misses(fog_blend, tmp_path, monkeypatch):
    from xsl_render.addon.cycles import selective_render
    from xsl_render.addon.scene.blend_session import open_blend
    from xsl_render.addon.validation import reference as ref

    environ = {"XSL_RENDER_CACHE": str(tmp_path)}
    calls = []
    real = selective_render.render_uniform

    def counted(*args, **kwargs):
        calls.append(kwargs.get("spp"))
        return real(*args, **kwargs)
    monkeypatch.setattr(ref, "render_uniform", counted)
    scene = open_blend(fog_blend)
    inputs = ref.reference_inputs(scene, fog_blend, spp=16)
    assert (inputs.resolution, inputs.seed, inputs.frame) == ((W, H), REFERENCE_SEED, scene.frame_current)
    first = ref.ensure_reference(scene, inputs, environ=environ)
    assert first.source == "rendered" and calls == [16]
    again = ref.ensure_reference(scene, inputs, environ=environ)
    assert again.source == "cache" and calls == [16] and again.path == first.path
    # The same pixels as an ordinary uniform render with that seed, denoised the same way.
    from xsl_render.core.sampling.render_options import RenderOptions

    plain = real(scene, RenderOptions(max_spp=16, seed=REFERENCE_SEED), spp=16)
    assert np.array_equal(read_image(first.path), plain.image)
    for changed in (ref.reference_inputs(scene, fog_blend, spp=17),
                    ref.reference_inputs(scene, fog_blend, spp=16, seed=8),
                    ref.reference_inputs(scene, fog_blend, spp=16, resolution=(W - 2, H))):
        assert changed.key != inputs.key
        assert ref.ensure_reference(scene, changed, environ=environ).source == "rendered"
    assert calls == [16, 17, 16, 16]


@pytest.mark.blender
@pytest.mark.render
def test_a_cancelled_reference_writes_nothing(fog_blend, tmp_path):
    from xsl_render.addon.scene.blend_session import open_blend
    from xsl_render.addon.validation import reference as ref

    environ = {"XSL_RENDER_CACHE": str(tmp_path)}
    scene = open_blend(fog_blend)
    inputs = ref.reference_inputs(scene, fog_blend, spp=8)
    with pytest.raises(Cancelled):
        ref.ensure_reference(scene, inputs, progress=lambda fraction, message: True, environ=environ)
    assert not any(p.is_file() for p in tmp_path.rglob("*"))


@pytest.mark.blender
@pytest.mark.render
def test_cli_renders_then_copies_from_the_cache(fog_blend, tmp_path, reference_cache):
    args = ("reference", fog_blend, "--spp", "8", "--resolution", f"{W}x{H}", "--quiet")
    first = xsl_render_cli(*args, "--out", tmp_path / "a.exr")
    assert first.returncode == 0, first.stderr
    assert first.stdout.startswith(f"reference: rendered {W}x{H}, 8 spp, seed 7, frame 1")
    second = xsl_render_cli(*args, "--out", tmp_path / "b.exr")
    assert second.returncode == 0, second.stderr
    assert second.stdout.startswith("reference: cached (user cache)")
    assert np.array_equal(read_image(tmp_path / "a.exr"), read_image(tmp_path / "b.exr"))
    key = first.stderr.strip().split()[-1]
    assert (reference_cache / "references" / f"{key}.json").is_file()


@pytest.mark.blender
@pytest.mark.render
def test_references_of_frames_keep_the_finished_ones_when_cancelled(fog_blend, tmp_path):
    """Frame by frame in one session: a cancel before frame 2 keeps frame 1's entry, writes
    none for frame 2, and leaves the scene's frame and persistent data as they were."""
    from xsl_render.addon.scene.blend_session import open_blend
    from xsl_render.addon.validation import reference as ref

    environ = {"XSL_RENDER_CACHE": str(tmp_path)}
    scene = open_blend(fog_blend)
    frame, persistent = scene.frame_current, scene.render.use_persistent_data
    inputs = [ref.reference_inputs(scene, fog_blend, spp=2, frame=f) for f in (1, 2)]
    finished = []

    def progress(fraction, message):
        return message.startswith("frame 2")
    with pytest.raises(Cancelled):
        ref.ensure_references(scene, inputs, progress=progress, environ=environ, on_frame=finished.append)
    assert [r.inputs.frame for r in finished] == [1] and finished[0].source == "rendered"
    assert find_reference(inputs[0].key, environ) is not None
    assert find_reference(inputs[1].key, environ) is None
    assert (scene.frame_current, scene.render.use_persistent_data) == (frame, persistent)
    done = ref.ensure_references(scene, inputs, environ=environ)
    assert [r.source for r in done] == ["cache", "rendered"]


@pytest.mark.blender
@pytest.mark.render
def test_cli_frames_of_the_street_each_cached(tmp_path):
    """reference --frames on the moving example: one file per frame, different frames (the
    camera moves), the same entries a single --frame finds; a second call renders nothing."""
    street = EXAMPLES / "street.blend"
    args = ("reference", street, "--resolution", "32x18", "--spp", "4", "--quiet")
    first = xsl_render_cli(*args, "--frames", "1-2", "--out", tmp_path / "a" / "frame_####.exr")
    assert first.returncode == 0, first.stderr
    lines = first.stdout.strip().splitlines()
    assert lines[0].startswith("reference: rendered 32x18, 4 spp, seed 7, frame 1 in ")
    assert lines[1].startswith("reference: rendered 32x18, 4 spp, seed 7, frame 2 in ")
    assert lines[-1] == "reference: 2 frames, 2 rendered, 0 from the cache"
    one, two = (read_image(tmp_path / "a" / f"frame_000{f}.exr") for f in (1, 2))
    assert one.shape == two.shape == (18, 32, 4) and not np.array_equal(one, two)
    again = xsl_render_cli(*args, "--frames", "1-2", "--out", tmp_path / "b" / "ref.exr")
    assert again.returncode == 0, again.stderr
    assert again.stdout.strip().splitlines()[-1] == "reference: 2 frames, 0 rendered, 2 from the cache"
    assert np.array_equal(read_image(tmp_path / "b" / "ref0002.exr"), two)
    single = xsl_render_cli(*args, "--frame", "2", "--out", tmp_path / "c.exr")
    assert single.returncode == 0, single.stderr
    assert single.stdout.startswith("reference: cached (user cache) 32x18, 4 spp, seed 7, frame 2")


@pytest.mark.blender
@pytest.mark.render
def test_ctrl_c_twice_stops_the_render_and_writes_nothing(fog_blend, tmp_path):
    exe = Path(sys.executable).with_name("xsl-render")
    cache = tmp_path / "cache"
    process = subprocess.Popen(
        [str(exe), "reference", str(fog_blend), "--spp", "200000", "--out", str(tmp_path / "r.exr")],
        stderr=subprocess.PIPE, text=True, env={**os.environ, "XSL_RENDER_CACHE": str(cache)})
    line = ""
    while "rendering" not in line:                    # the progress bar: the render begins
        line = process.stderr.readline()
        assert line, "the command ended before rendering"
    process.send_signal(signal.SIGINT)                 # asks to stop after the render ...
    process.stderr.readline()
    process.send_signal(signal.SIGINT)                 # ... and the second stops it now
    process.communicate(timeout=60)
    assert process.returncode == 130
    assert not (tmp_path / "r.exr").exists()
    assert not [p for p in cache.rglob("*") if p.is_file()]


@pytest.mark.parametrize("extra, message", [
    (("--spp", "0"), "--spp: must be a whole number from 1 to 16777216"),
    (("--spp", "-4"), "--spp: must be a whole number from 1 to 16777216"),
    (("--spp", "many"), "--spp: must be a whole number, not 'many'"),
    (("--seed", "-1"), "--seed: must be a whole number from 0 to 2147483647"),
    (("--max-spp", "0"), "--max-spp: must be a whole number from 1 to 1048576"),
    (("--out", "r.png"), "must be a .exr file"),
    (("--frames", "3-1"), "--frames 3-1: the end frame 1 is before the start frame 3"),
    (("--frames", "1-2", "--frame", "1"), "--frame and --frames cannot be combined"),
])
@pytest.mark.blender          # the command line, as a user runs it
def test_bad_values_exit_2_with_one_line(extra, message, tmp_path):
    args = ["reference", EXAMPLES / "road.blend", "--out", tmp_path / "r.exr"]
    if extra[0] == "--out":
        args = args[:2] + ["--out", tmp_path / extra[1]]
    else:
        args += list(extra)
    assert message in one_line_error(xsl_render_cli(*args))
