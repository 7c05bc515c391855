"""``xsl-render saliency IMAGE --out FILE.exr``, run as a user runs it."""
from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio
import pytest
from skimage.draw import disk

from xsl_render.core.imageio import image_channel_names, read_image

HEIGHT, WIDTH = 96, 128
BRIGHT = (40, 84)           # centre of the odd, bright disc


def _display(levels=(0.45, 1.0)):
    """Grey discs on black, one brighter: a pop-out any channel layout can carry."""
    image = np.zeros((HEIGHT, WIDTH), np.float32)
    for row in range(16, HEIGHT, 32):
        for col in range(20, WIDTH, 32):
            rr, cc = disk((row, col), 7, shape=image.shape)
            image[rr, cc] = levels[0]
    rr, cc = disk(BRIGHT, 7, shape=image.shape)
    image[rr, cc] = levels[1]
    return image


def _write(path, array, fmt):
    array = np.ascontiguousarray(array if array.ndim == 3 else array[:, :, None])
    spec = oiio.ImageSpec(array.shape[1], array.shape[0], array.shape[2], fmt)
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec) and out.write_image(array)
    out.close()
    return path


def _grey_png(path):
    return _write(path, np.round(_display() * 255).astype(np.uint8), oiio.UINT8)


def _rgba_png(path):
    rgba = np.zeros((HEIGHT, WIDTH, 4), np.uint8)
    rgba[:, :, :3] = np.round(_display()[:, :, None] * 255)
    rgba[:, :, 3] = 255
    return _write(path, rgba, oiio.UINT8)


def _png16(path):
    rgb = np.repeat(np.round(_display()[:, :, None] * 65535), 3, axis=2).astype(np.uint16)
    return _write(path, rgb, oiio.UINT16)


def _jpeg(path):
    rgb = np.repeat(np.round(_display()[:, :, None] * 255), 3, axis=2).astype(np.uint8)
    return _write(path, rgb, oiio.UINT8)


def _hdr_exr(path):
    # scene-linear, far above 1: the discs at 20 and 400 (the tone map has to bring them in)
    rgb = np.repeat(_display(levels=(20.0, 400.0))[:, :, None], 3, axis=2)
    return _write(path, rgb.astype(np.float32), oiio.HALF)


@pytest.mark.parametrize("make", [_grey_png, _rgba_png, _png16, _jpeg, _hdr_exr],
                         ids=["grey8", "rgba8", "rgb16", "jpeg", "hdr-exr"])
def test_saliency_of_any_image_file(cli, tmp_path, make):
    source = make(tmp_path / ("in.exr" if make is _hdr_exr else
                              "in.jpg" if make is _jpeg else "in.png"))
    out = tmp_path / "maps" / "s.exr"
    preview = tmp_path / "s.png"
    done = cli("saliency", source, "--out", out, "--png", preview)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    smap = read_image(out)
    assert smap.shape == (HEIGHT, WIDTH, 1)
    assert image_channel_names(out) == ["Y"]
    spec = oiio.ImageInput.open(str(out))
    assert spec.spec().format == oiio.FLOAT
    spec.close()
    assert np.isfinite(smap).all() and smap.min() == 0.0 and smap.max() == pytest.approx(1.0)
    row, col = np.unravel_index(np.argmax(smap[:, :, 0]), smap.shape[:2])
    assert abs(row - BRIGHT[0]) <= 10 and abs(col - BRIGHT[1]) <= 10
    assert read_image(preview).shape == (HEIGHT, WIDTH, 1)
    assert sorted(p.name for p in out.parent.iterdir()) == ["s.exr"]     # no temporary left


def _one_pixel(tmp_path):
    return _write(tmp_path / "one.png", np.zeros((1, 1, 3), np.uint8), oiio.UINT8)


def _one_row(tmp_path):
    return _write(tmp_path / "row.png", np.zeros((1, 30, 3), np.uint8), oiio.UINT8)


def _empty_file(tmp_path):
    path = tmp_path / "empty.png"
    path.write_bytes(b"")
    return path


def _garbage(tmp_path):
    path = tmp_path / "garbage.exr"
    path.write_bytes(b"this is not an image\n" * 10)
    return path


def _missing(tmp_path):
    return tmp_path / "missing.png"


@pytest.mark.parametrize("make, words", [
    (_one_pixel, "1x1"), (_one_row, "30x1"), (_empty_file, "cannot read"),
    (_garbage, "cannot read"), (_missing, "no such image"),
], ids=["1x1", "1x30", "empty-file", "not-an-image", "missing"])
def test_bad_images_exit_2_with_one_line(cli, tmp_path, make, words):
    out = tmp_path / "s.exr"
    done = cli("saliency", make(tmp_path), "--out", out)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], done.stderr
    assert "Traceback" not in done.stderr
    assert not out.exists()


def _under_a_file(tmp_path):
    blocker = tmp_path / "blocker"
    blocker.write_text("a file, not a folder")
    return blocker / "s.exr"


@pytest.mark.parametrize("out, words", [
    (_under_a_file, "not a folder"),
    (lambda tmp: tmp / "s.png", "must be a .exr"),
    (lambda tmp: tmp, "is a folder"),
], ids=["folder-is-a-file", "wrong-extension", "out-is-a-folder"])
def test_bad_outputs_exit_2_before_any_work(cli, tmp_path, out, words):
    source = _grey_png(tmp_path / "in.png")
    done = cli("saliency", source, "--out", out(tmp_path))
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], done.stderr


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0,
                    reason="needs POSIX permissions that apply to this user")
def test_read_only_folder_exits_2(cli, tmp_path):
    source = _grey_png(tmp_path / "in.png")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        done = cli("saliency", source, "--out", locked / "s.exr")
    finally:
        locked.chmod(0o700)
    assert done.returncode == 2
    assert "not writable" in done.stderr and len(done.stderr.strip().splitlines()) == 1


def test_saliency_command_never_imports_bpy(tmp_path):
    source = _grey_png(tmp_path / "in.png")
    code = ("import sys\n"
            "from xsl_render.operators.cli import main\n"
            f"code = main(['saliency', {str(source)!r}, '--out', {str(tmp_path / 's.exr')!r}])\n"
            "assert code == 0, code\n"
            "assert 'bpy' not in sys.modules\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
