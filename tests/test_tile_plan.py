"""The tile plan: per-pixel targets, the tile quantile, merging, JSON, costs (no Blender)."""
from __future__ import annotations

import json

import numpy as np
import pytest
from support.cli_wording import refused_in_flags

from xsl_render.core.camera import CameraModel, border_for_window
from xsl_render.core.errors import InputError
from xsl_render.core.sampling.render_options import RenderOptions, parse_resolution
from xsl_render.core.sampling.tile_plan import (Rect, TilePlan, check_director_map, make_plan,
                                                merge_rects, quantise_up, split_tile, spp_ladder,
                                                target_spp, tile_windows)

WHOLE = 10 ** 12            # a render cost that never pays for splitting a tile


def random_map(height, width, seed=0, smooth=True):
    rng = np.random.default_rng(seed)
    data = rng.random((height, width))
    if smooth:      # director maps are smooth: blurred saliency, transmittance, glow
        for _ in range(6):
            data = 0.25 * (np.roll(data, 1, 0) + np.roll(data, -1, 0) + np.roll(data, 1, 1) + np.roll(data, -1, 1))
        data = (data - data.min()) / (data.max() - data.min())
    return data.astype(np.float32)


@pytest.mark.parametrize("max_spp,min_spp", [(16, 1), (64, 1), (64, 4), (1, 1)])
def test_target_is_the_papers_weighting_with_a_floor(max_spp, min_spp):
    data = np.array([[0.0, 0.01, 0.5, 1.0], [0.24, 0.26, 0.99, 0.75]], np.float32)
    targets = target_spp(data, max_spp, min_spp)
    expected = np.maximum(min_spp, np.rint(max_spp * data.astype(np.float64)))
    assert targets.dtype == np.int32
    np.testing.assert_array_equal(targets, expected)
    assert targets.max() == max_spp and targets.min() >= min_spp


def tile_grid(targets, tile_size, quantile=1.0, render_cost=WHOLE):
    height, width = targets.shape
    return [rect for window in tile_windows(width, height, tile_size)
            for rect in split_tile(targets, window, quantile, render_cost)]


def grid_rects(grid, tile_size, width, height):
    return [Rect(r * tile_size, min(height, (r + 1) * tile_size), c * tile_size,
                 min(width, (c + 1) * tile_size), int(grid[r, c]))
            for r in range(grid.shape[0]) for c in range(grid.shape[1])]


def test_tile_takes_the_maximum_by_default():
    targets = np.ones((64, 64), np.int32)
    targets[5, 40] = 50                     # one salient pixel in tile (0, 1)
    assert [rect.spp for rect in tile_grid(targets, 32)] == [1, 50, 1, 1]


@pytest.mark.parametrize("quantile", [0.5, 0.9, 0.95, 1.0])
def test_tile_quantile_starves_at_most_the_rest(quantile):
    targets = target_spp(random_map(96, 128, smooth=False), 64, 1)
    for rect in tile_grid(targets, 16, quantile):
        block = targets[rect.row0:rect.row1, rect.col0:rect.col1]
        assert rect.spp in block                                # an actual pixel's target
        assert (block <= rect.spp).mean() >= quantile           # at least that share fully served


def test_partial_edge_tiles_only_look_at_their_own_pixels():
    targets = np.ones((40, 70), np.int32)
    targets[39, 69] = 9
    rects = tile_grid(targets, 32)
    assert [rect.window for rect in rects][-1] == (32, 40, 64, 70)
    assert [rect.spp for rect in rects] == [1, 1, 1, 1, 1, 9]


@pytest.mark.parametrize("render_cost,renders", [(0, 7), (3000, 7), (5000, 4), (20000, 1), (WHOLE, 1)])
def test_tiles_split_where_the_samples_saved_pay_for_the_renders(render_cost, renders):
    targets = np.ones((32, 32), np.int32)
    targets[3, 3] = 64                      # one salient pixel in the top-left 8x8 corner
    rects = split_tile(targets, (0, 32, 0, 32), 1.0, render_cost)
    assert len(rects) == renders
    salient = [rect for rect in rects if rect.spp == 64]
    assert len(salient) == 1 and (salient[0].row0, salient[0].col0) == (0, 0)
    if renders == 7:                        # quadrants of quadrants: 3 of 16 px, 4 of 8 px
        assert salient[0].area == 64 and sum(r.samples for r in rects) == 64 * 64 + 1024 - 64


def test_equal_tiles_merge_into_one_rectangle():
    plan = make_plan(np.full((54, 96), 0.5, np.float32), RenderOptions(max_spp=16, tile_size=16))
    assert plan.rects == [Rect(0, 54, 0, 96, 8)]


def test_merging_runs_and_stacks():
    grid = np.array([[1, 1, 2, 2],
                     [1, 1, 2, 3],
                     [4, 4, 4, 4]], np.int32)
    rects = merge_rects(grid_rects(grid, 10, width=35, height=25))
    assert rects == [Rect(0, 20, 0, 20, 1), Rect(0, 10, 20, 35, 2), Rect(10, 20, 20, 30, 2),
                     Rect(10, 20, 30, 35, 3), Rect(20, 25, 0, 35, 4)]


def test_checkerboard_does_not_merge():
    grid = (np.indices((3, 4)).sum(0) % 2 + 1).astype(np.int32)
    assert len(merge_rects(grid_rects(grid, 8, 32, 24))) == 12


@pytest.mark.parametrize("height,width,tile,quantile,levels,seed", [
    (36, 64, 8, 1.0, 0, 0), (54, 96, 16, 0.95, 0, 1), (288, 512, 32, 1.0, 0, 2),
    (288, 512, 32, 1.0, 6, 3), (100, 37, 9, 0.9, 3, 4), (17, 200, 16, 1.0, 0, 5)])
def test_plan_covers_the_frame_once_and_never_starves(height, width, tile, quantile, levels, seed):
    data = random_map(height, width, seed)
    options = RenderOptions(max_spp=64, min_spp=2, tile_size=tile, tile_quantile=quantile, spp_levels=levels)
    plan = make_plan(data, options)
    plan.check()
    spp = plan.spp_image()
    targets = target_spp(data, 64, 2)
    assert plan.total_samples == int(spp.sum())
    assert plan.gold_samples == width * height * 64
    assert plan.ideal_speedup == pytest.approx(plan.gold_samples / spp.sum())
    assert plan.mean_spp == pytest.approx(spp.mean())
    assert plan.target_samples == int(targets.sum())
    if quantile == 1.0:
        assert (spp >= targets).all()
    unsplit = make_plan(data, RenderOptions(max_spp=64, min_spp=2, tile_size=tile, tile_quantile=quantile,
                                            spp_levels=levels, render_cost=WHOLE))
    assert len(unsplit.rects) <= -(-height // tile) * -(-width // tile)
    assert plan.total_samples + 1024 * len(plan.rects) <= unsplit.total_samples + 1024 * len(unsplit.rects)
    if levels:
        assert len({rect.spp for rect in plan.rects}) <= levels


def test_json_round_trip():
    plan = make_plan(random_map(54, 96, 7), RenderOptions(max_spp=16, tile_size=16, tile_quantile=0.95))
    text = json.dumps(plan.to_dict())
    again = TilePlan.from_dict(json.loads(text))
    assert again.rects == plan.rects
    assert again.to_dict() == plan.to_dict()
    data = json.loads(text)
    assert data["renders"] == len(data["rects"])
    assert data["total_samples"] == sum((r["row1"] - r["row0"]) * (r["col1"] - r["col0"]) * r["spp"]
                                        for r in data["rects"])


def test_json_with_a_hole_is_refused():
    data = make_plan(random_map(54, 96, 8), RenderOptions(max_spp=16, tile_size=16)).to_dict()
    data["rects"] = data["rects"][1:]
    with pytest.raises(InputError, match="cover"):
        TilePlan.from_dict(data)


@pytest.mark.parametrize("levels,low,high", [(2, 1, 64), (5, 1, 64), (7, 4, 16), (9, 1, 4)])
def test_quantised_levels_round_up(levels, low, high):
    ladder = spp_ladder(levels, low, high)
    assert ladder[0] == low and ladder[-1] == high and len(ladder) <= levels
    values = np.arange(low, high + 1)
    rounded = quantise_up(values, ladder)
    assert (rounded >= values).all() and set(rounded) <= set(ladder)


@pytest.mark.parametrize("data,message", [
    (np.zeros((36, 65)), "65x36 but the render is 64x36"),
    (np.full((36, 64), np.nan), "NaN"),
    (np.full((36, 64), 1.5), r"\[0, 1\]"),
    (np.full((36, 64), -0.2), r"\[0, 1\]"),
    (np.zeros((36, 64, 2)), "one channel"),
    (np.zeros(5), "image"),
])
def test_bad_director_maps(data, message):
    with pytest.raises(InputError, match=message):
        check_director_map(data, 64, 36)


def test_grey_rgba_map_is_accepted():
    grey = np.dstack([np.full((36, 64), 0.25)] * 3 + [np.ones((36, 64))])
    assert check_director_map(grey, 64, 36).shape == (36, 64)


@pytest.mark.parametrize("changes,message", [
    ({"max_spp": 0}, "max-spp"), ({"min_spp": 0}, "min-spp"), ({"min_spp": 65}, "larger than"),
    ({"tile_size": 4}, "tile-size"), ({"tile_quantile": 0.0}, "quantile"),
    ({"spp_levels": 1}, "spp-levels"), ({"seed": -1}, "seed"), ({"margin": 100}, "margin"),
    ({"render_cost": -1}, "render-cost"), ({"adaptive_threshold": 0.0}, "adaptive-threshold"), ({"resolution": (0, 10)}, "resolution")])
def test_bad_options(changes, message):
    options = RenderOptions(**({"max_spp": 64} | changes))
    with refused_in_flags(message):
        options.check()


def test_tile_larger_than_the_frame():
    with pytest.raises(InputError, match="larger than the 64x36 frame"):
        make_plan(np.zeros((36, 64), np.float32), RenderOptions(max_spp=4, tile_size=72))


@pytest.mark.parametrize("text,expected", [("512x288", (512, 288)), ("64X36", (64, 36))])
def test_parse_resolution(text, expected):
    assert parse_resolution(text) == expected


@pytest.mark.parametrize("text", ["512", "ax3", "0x10", "5x5x5"])
def test_parse_resolution_refuses(text):
    with pytest.raises(InputError):
        parse_resolution(text)


@pytest.mark.parametrize("width,height", [(64, 36), (97, 55), (512, 288), (1920, 1080)])
def test_border_for_window_selects_exactly_the_window(width, height):
    rng = np.random.default_rng(width)
    for _ in range(50):
        r0, r1 = sorted(rng.choice(height + 1, 2, replace=False))
        c0, c1 = sorted(rng.choice(width + 1, 2, replace=False))
        border = border_for_window((r0, r1, c0, c1), width, height)
        camera = CameraModel(kind="PERSP", matrix_world=np.eye(4), width=width, height=height,
                             border=tuple(np.float32(border)))          # Blender stores float32
        assert camera.pixel_window() == (r0, r1, c0, c1)
        # Blender and Cycles truncate: the same pixels.
        f = np.float32(border)
        assert (int(f[0] * width), int(f[2] * width)) == (c0, c1)
        assert (int(f[1] * height), int(f[3] * height)) == (height - r1, height - r0)
