"""Finding the frames of a sequence by pattern or folder and matching two sequences by
frame number (core/validation/frame_sequence.py), with one-line errors naming the frame."""
from __future__ import annotations

import numpy as np
import pytest
from support.cli_wording import refused_in_flags

from xsl_render.core.errors import InputError
from xsl_render.core.imageio import write_exr
from xsl_render.core.validation.frame_sequence import check_frames, find_frames, match_frames

H, W = 24, 40


def write_sequence(folder, frames, name="frame_{:04d}.exr", seed=0, sigma=0.0, size=(H, W)):
    """Scene-linear frames: a gradient, a bright square moving right, optionally per-frame noise."""
    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True, exist_ok=True)
    height, width = size
    rows, cols = np.mgrid[0:height, 0:width].astype(np.float32)
    for frame in frames:
        image = np.stack([0.05 + 0.3 * cols / width + 0.05 * (frame % 5), 0.05 + 0.3 * rows / height,
                          np.full_like(rows, 0.15)], 2)
        image[6:14, 3 * frame:3 * frame + 8] = 0.6
        image = np.maximum(image + rng.normal(0, sigma, image.shape).astype(np.float32), 0.0)
        write_exr(folder / name.format(frame), image)
    return folder


@pytest.mark.parametrize("given, frames, expected", [
    ("ref/frame_####.exr", None, [1, 2, 3, 10]),
    ("ref/frame_####", None, [1, 2, 3, 10]),            # .exr added as Blender's naming does
    ("ref/frame_##.exr", None, []),                       # frame_0001 is not what ## writes
    ("ref/frame_####.exr", "2-3", [2, 3]),
    ("ref", None, [1, 2, 3, 7, 10]),                      # a folder: every numbered .exr
    ("ref", "1,10", [1, 10]),
])
def test_frames_are_found_by_pattern_or_folder(tmp_path, monkeypatch, given, frames, expected):
    from xsl_render.core.frames import parse_frame_list

    write_sequence(tmp_path / "ref", [1, 2, 3, 10])
    write_sequence(tmp_path / "ref", [7], name="frame_{}.exr")   # not ####-padded
    (tmp_path / "ref" / ".frame_0004.exr.123-abcdef12.partial.exr").write_bytes(b"")  # a temporary
    (tmp_path / "ref" / "notes.txt").write_text("not a frame")
    for name in ("frame_0002_spp.exr", "beauty.exr"):          # an animation's samples map; no number
        write_exr(tmp_path / "ref" / name, np.zeros((2, 2, 3), np.float32))
    monkeypatch.chdir(tmp_path)
    wanted = parse_frame_list(frames) if frames else None
    if not expected:
        with pytest.raises(InputError, match="names no existing frame"):
            find_frames(given, "REF", wanted)
        return
    assert list(find_frames(given, "REF", wanted).frames) == expected


@pytest.mark.parametrize("case, words", [
    ("two-of-one-frame", "two files of frame 2"),
    ("missing-in-test", "frame 3 is in REF but not in TEST"),
    ("missing-of-frames", "TEST has no frame 2 of --frames"),
    ("size", "every frame must have one size"),
    ("channels", "differ in channel count"),
])
def test_bad_sequences_are_refused_naming_the_frame(tmp_path, case, words):
    ref = write_sequence(tmp_path / "ref", [1, 2, 3])
    test = write_sequence(tmp_path / "test", [1, 2, 3])
    frames = None
    if case == "two-of-one-frame":
        write_exr(test / "other_2.exr", np.zeros((H, W, 3), np.float32))
    elif case == "missing-in-test":
        (test / "frame_0003.exr").unlink()
    elif case == "missing-of-frames":
        (test / "frame_0002.exr").unlink()
        frames = (1, 2)
    elif case == "size":
        write_sequence(test, [2], size=(H, W + 2))
    elif case == "channels":
        write_exr(test / "frame_0002.exr", np.zeros((H, W, 4), np.float32))
    with refused_in_flags(words):
        pairs = match_frames(find_frames(str(ref), "REF", frames), find_frames(str(test), "TEST", frames), frames)
        check_frames(pairs)
