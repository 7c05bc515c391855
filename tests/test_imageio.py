"""Image files: round trips, atomic writes, refusing NaN, clear errors for bad files."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from xsl_render.core.errors import InputError
from xsl_render.core.files import atomic_path, atomic_paths
from xsl_render.core.imageio import image_channel_names, read_image, write_exr, write_png


@pytest.mark.parametrize("shape, names", [((5, 7), ["Y"]), ((5, 7, 3), ["R", "G", "B"]),
                                          ((5, 7, 4), ["R", "G", "B", "A"])])
def test_exr_round_trip_is_exact_float32(tmp_path, shape, names):
    data = np.random.default_rng(0).uniform(0, 50, shape).astype(np.float32)
    path = write_exr(tmp_path / "x.exr", data)
    back = read_image(path)
    np.testing.assert_array_equal(back.reshape(data.shape), data)
    assert image_channel_names(path) == names


def test_png_preview_holds_the_map_values(tmp_path):
    data = np.linspace(0, 1, 256, dtype=np.float32).reshape(16, 16)
    back = read_image(write_png(tmp_path / "p.png", data))
    np.testing.assert_allclose(back[:, :, 0], data, atol=0.5 / 255)


def test_nan_never_reaches_a_file(tmp_path):
    data = np.zeros((4, 4), np.float32)
    data[1, 2] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        write_exr(tmp_path / "bad.exr", data)
    assert list(tmp_path.iterdir()) == []


def test_atomic_path_leaves_nothing_behind_on_failure(tmp_path):
    target = tmp_path / "out.exr"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("cancelled")
    assert list(tmp_path.iterdir()) == []


def test_atomic_path_replaces_on_success(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with atomic_path(target) as tmp:
        tmp.write_text("new")
    assert target.read_text() == "new" and len(list(tmp_path.iterdir())) == 1


def test_atomic_paths_rename_the_whole_set_last_named_last_or_nothing(tmp_path, monkeypatch):
    names = ["a.exr", "b.png", "record.json"]
    for name in names:
        (tmp_path / name).write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_paths(*(tmp_path / name for name in names)) as temporaries:
            temporaries[0].write_text("new")
            temporaries[1].write_text("new")
            raise RuntimeError("killed before the record")
    assert sorted(p.name for p in tmp_path.iterdir()) == names
    assert all((tmp_path / name).read_text() == "old" for name in names)

    renamed, replace = [], os.replace
    monkeypatch.setattr(os, "replace", lambda src, dst: (renamed.append(Path(dst).name), replace(src, dst)))
    with atomic_paths(*(tmp_path / name for name in names)) as temporaries:
        assert [t.suffix for t in temporaries] == [".exr", ".png", ".json"]
        for tmp in temporaries:
            tmp.write_text("new")
        assert all((tmp_path / name).read_text() == "old" for name in names)
    assert renamed == names                                   # the record goes last
    assert all((tmp_path / name).read_text() == "new" for name in names)
    assert sorted(p.name for p in tmp_path.iterdir()) == names


def test_missing_and_unreadable_files_are_input_errors(tmp_path):
    with pytest.raises(InputError, match="no such image"):
        read_image(tmp_path / "nope.png")
    junk = tmp_path / "junk.png"
    junk.write_bytes(b"not an image at all")
    with pytest.raises(InputError, match="cannot read"):
        read_image(junk)
