"""Embree's single-precision arithmetic replayed (``core.maps.embree_ties``): the distances
it computes, and the share of Cycles' samples that meet two coincident faces at the same
float. What Cycles renders there is checked in ``test_xmap_coincident.py``."""
from __future__ import annotations

import math

import numpy as np
import pytest

from xsl_render.core.camera import CameraModel
from xsl_render.core.maps.camera_rays import CameraRays, fit_ray_model
from xsl_render.core.maps.embree_ties import (blackman_harris_offsets, camera_samples,
                                              cycles_world_vertices, embree_distance,
                                              exact_tie_fractions, exact_ties)

#: The fog box of ``test_xmap_coincident._fog_box_on_the_ground`` as Cycles holds it: its
#: bottom's two triangles, and the floor's (a plane of size 40, or 32).
BOX_BOTTOM = np.array([[[-8, 12, 0], [8, 12, 0], [8, -4, 0]],
                       [[-8, 12, 0], [8, -4, 0], [-8, -4, 0]]], dtype=np.float32)


def _floor(size: float) -> np.ndarray:
    lo, hi = -size / 2, size / 2
    return np.array([[[lo, 4 + lo, 0], [hi, 4 + lo, 0], [hi, 4 + hi, 0]],
                     [[lo, 4 + lo, 0], [hi, 4 + hi, 0], [lo, 4 + hi, 0]]], dtype=np.float32)


def _euler_matrix(location, degrees) -> np.ndarray:
    x, y, z = (math.radians(a) for a in degrees)
    rx = np.array([[1, 0, 0], [0, math.cos(x), -math.sin(x)], [0, math.sin(x), math.cos(x)]])
    rz = np.array([[math.cos(z), -math.sin(z), 0], [math.sin(z), math.cos(z), 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = rz @ rx
    m[:3, 3] = location
    return m


def _camera_inside_the_box(width=32, height=18):
    """The camera of the coincident-face tests, in the box, looking down at the floor."""
    camera = CameraModel(kind="PERSP", matrix_world=_euler_matrix((0.0, -2.0, 1.5), (60, 0, 10)),
                         width=width, height=height, lens=24.0, sensor_width=36.0)
    origins, directions = camera.pixel_rays()
    near, far = camera.clip_range(directions)
    rays = CameraRays(size=(height, width), window=(0, height, 0, width), origins=origins,
                      directions=directions, t_near=near, t_far=far,
                      hit=np.ones((height, width), bool), view_axis=camera.view_axis())
    return camera, rays, fit_ray_model(rays)


def _triangle_under(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Which of two triangles that split a rectangle along its diagonal holds each point."""
    a, c = triangles[0, 0].astype(float), triangles[0, 2].astype(float)
    b = triangles[0, 1].astype(float)
    side = np.cross(c - a, points - a)[:, 2] * np.cross(c - a, b - a)[2]
    return np.where(side > 0, 0, 1)


def _pixels_on_the_box_bottom(rays):
    t = -rays.origins[..., 2] / rays.directions[..., 2]
    points = rays.origins + rays.directions * t[..., None]
    inside = (t > 0) & (np.abs(points[..., 0]) < 7.9) & (points[..., 1] > -3.9) & (points[..., 1] < 11.9)
    rows, cols = np.nonzero(inside)
    return rows, cols, points[rows, cols]


@pytest.mark.parametrize("seed", range(3))
def test_distance_is_the_single_precision_intersection(seed):
    rng = np.random.default_rng(seed)
    triangles = rng.uniform(-10, 10, (2000, 3, 3)).astype(np.float32)
    weights = rng.dirichlet([2, 2, 2], 2000)
    target = np.einsum("nk,nkj->nj", weights, triangles.astype(np.float64))
    origins = rng.uniform(-30, 30, (2000, 3)).astype(np.float32)
    directions = target - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    directions = directions.astype(np.float32)
    tri = triangles.astype(np.float64)
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    exact = (np.einsum("nj,nj->n", normal, tri[:, 0] - origins)
             / np.einsum("nj,nj->n", normal, directions.astype(np.float64)))
    t = embree_distance(origins, directions, triangles)
    assert t.dtype == np.float32
    # Rays nearly in the triangle's plane lose digits; the rest agree to a few floats.
    steep = np.abs(np.einsum("nj,nj->n", normal / np.linalg.norm(normal, axis=1, keepdims=True),
                             directions)) > 0.2
    assert np.all(np.abs(t - exact)[steep] <= 2e-5 * np.abs(exact[steep]))


def test_world_vertices_are_rounded_step_by_step_in_single_precision():
    local = np.array([[1.0, 1.0, -1.0], [0.1, 0.2, 0.3]])
    matrix = np.diag([8.0, 8.0, 3.0, 1.0])
    matrix[:3, 3] = (0.0, 4.0, 3.0)
    world = cycles_world_vertices(local, matrix)
    assert world.dtype == np.float32
    assert world[0].tolist() == [8.0, 12.0, 0.0]               # the box's corner, exactly
    f = np.float32
    expected_z = f(f(3.0) + f(f(0.3) * f(3.0)))
    assert world[1, 2] == expected_z
    assert np.allclose(world[1], local[1] @ matrix[:3, :3].T + matrix[:3, 3], rtol=1e-6)


def test_filter_offsets_stay_inside_the_filter():
    offsets = blackman_harris_offsets(np.random.default_rng(0), (100_000,), width=0.01)
    assert np.all(np.abs(offsets) <= 0.005)
    assert abs(offsets.mean()) < 1e-4
    # Blackman-Harris is narrow: its standard deviation is about a seventh of its width.
    assert 0.1 < offsets.std() / 0.01 < 0.2
    assert not blackman_harris_offsets(np.random.default_rng(0), (10,), width=0.0).any()


def test_camera_samples_start_on_the_near_plane():
    camera, rays, model = _camera_inside_the_box()
    rows, cols = np.array([3, 10]), np.array([5, 20])
    origins, directions = camera_samples(model, rows, cols, rays.view_axis, camera.clip_start,
                                         16, np.random.default_rng(0))
    o, d = np.stack(origins, -1).astype(float), np.stack(directions, -1).astype(float)
    assert o.shape == d.shape == (2, 16, 3)
    assert np.allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-6)
    depth = (o - camera.eye) @ rays.view_axis
    assert np.allclose(depth, camera.clip_start, rtol=1e-5)
    # Within a hundredth of a pixel of the centre rays.
    assert np.all(np.abs(d - rays.directions[rows, cols][:, None]) < 1e-3)


def test_a_floor_twice_the_box_ties_in_every_sample():
    """Cycles lets every sample through a 32-wide floor under a 16-wide box (a render: 1.00):
    both triangles' roundings are the same up to powers of two."""
    camera, rays, model = _camera_inside_the_box()
    rows, cols, points = _pixels_on_the_box_bottom(rays)
    floor = _floor(32)
    first = BOX_BOTTOM[_triangle_under(points, BOX_BOTTOM)]
    second = floor[_triangle_under(points, floor)]
    origins, directions = camera_samples(model, rows, cols, rays.view_axis, camera.clip_start,
                                         32, np.random.default_rng(1))
    o, d = np.stack(origins, -1), np.stack(directions, -1)
    assert exact_ties(o, d, first[:, None], second[:, None]).all()


def test_a_floor_of_forty_ties_in_about_half_the_samples():
    """Under a 40-wide floor Cycles let 0.51 of the samples through (a render at 48x27);
    the replay finds as many exact ties, in bands: some pixels far more, some far less."""
    camera, rays, model = _camera_inside_the_box(64, 36)
    rows, cols, points = _pixels_on_the_box_bottom(rays)
    floor = _floor(40)
    first = BOX_BOTTOM[_triangle_under(points, BOX_BOTTOM)]
    second = floor[_triangle_under(points, floor)]
    fraction = exact_tie_fractions(model, rows, cols, rays.view_axis, camera.clip_start, first,
                                   second, np.zeros(len(rows)), 256, np.random.default_rng(2))
    assert 0.45 < fraction.mean() < 0.6
    assert np.percentile(fraction, 10) < 0.45 and np.percentile(fraction, 90) > 0.55


def test_pixels_with_few_rays_pool_them_with_their_band():
    camera, rays, model = _camera_inside_the_box(64, 36)
    rows, cols, points = _pixels_on_the_box_bottom(rays)
    floor = _floor(40)
    first = BOX_BOTTOM[_triangle_under(points, BOX_BOTTOM)]
    second = floor[_triangle_under(points, floor)]
    args = (model, rows, cols, rays.view_axis, camera.clip_start, first, second)
    pair = np.zeros(len(rows))
    alone = exact_tie_fractions(*args, pair, 128, np.random.default_rng(3))
    pooled = exact_tie_fractions(*args, pair, 128, np.random.default_rng(3), pool_side=4)
    many = exact_tie_fractions(*args, pair, 2048, np.random.default_rng(4))
    assert len(np.unique(pooled)) < len(rows) / 2
    # 128 rays a pixel leave 0.035 of noise; pooling in 4x4 cells halves it.
    assert np.abs(pooled - many).mean() < 0.8 * np.abs(alone - many).mean()
    # Identical triangles meet every ray at the same float.
    assert np.all(exact_tie_fractions(*args[:-1], first, pair, 4, np.random.default_rng(5)) == 1.0)
