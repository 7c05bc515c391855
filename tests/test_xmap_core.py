"""bpy-free parts of the X map: integration, MinBound, the ray cache, densities, noise hash."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from xsl_render.core.camera import CameraModel
from xsl_render.core.errors import InputError
from xsl_render.core.maps.camera_rays import (SKY_DEPTH, CameraRays, MediumIntervals,
                                              depth_from_exr, depth_to_exr, load_rays,
                                              planar_depth, ray_distance, save_rays)
from xsl_render.core.maps.xmap import (XMapWarning, apply_minbound, luminance, with_ties,
                                       x_from_transmittance, x_map_from_cached_rays)
from xsl_render.core.media.cycles_noise import hash_uint
from xsl_render.core.media.shader_graph import Node, ShaderGraph
from xsl_render.core.media.shader_link import Link
from xsl_render.core.media.shader_nodes import NodeContext, euler_matrix
from xsl_render.core.media.volume_medium import VolumeMedium, check_densities


def constant_medium(key="world:w", kind="world", density=0.1, color=(1.0, 1.0, 1.0),
                    node_type="VOLUME_SCATTER") -> VolumeMedium:
    node = Node(type=node_type, name="v", inputs={"Density": density, "Color": color},
                input_kinds={"Density": "VALUE", "Color": "RGBA"})
    graph = ShaderGraph(nodes={"v": node}, root=Link("v", "Volume", "SHADER"))
    return VolumeMedium(key=key, name=key, kind=kind, material=None, graph=graph)


def linear_medium(slope=0.2) -> VolumeMedium:
    """Density = slope * world x (a Texture Coordinate -> Separate XYZ -> Math chain)."""
    nodes = {
        "coord": Node(type="TEX_COORD", name="coord"),
        "split": Node(type="SEPXYZ", name="split", inputs={"Vector": Link("coord", "Object", "VECTOR")},
                      input_kinds={"Vector": "VECTOR"}),
        "scale": Node(type="MATH", name="scale", props={"operation": "MULTIPLY"},
                      inputs={"Value": Link("split", "X", "VALUE"), "Value_001": slope},
                      input_kinds={"Value": "VALUE", "Value_001": "VALUE"}),
        "v": Node(type="VOLUME_ABSORPTION", name="v",
                  inputs={"Density": Link("scale", "Value", "VALUE"), "Color": (0.0, 0.0, 0.0)},
                  input_kinds={"Density": "VALUE", "Color": "RGBA"}),
    }
    graph = ShaderGraph(nodes=nodes, root=Link("v", "Volume", "SHADER"))
    return VolumeMedium(key="world:w", name="w", kind="world", material=None, graph=graph)


def rays_along_x(lengths, hit=None, t_near=0.0) -> CameraRays:
    """1 x n rays from the origin along +x, stopping at ``lengths``."""
    lengths = np.asarray(lengths, dtype=np.float64)[None, :]
    n = lengths.shape[1]
    origins = np.zeros((1, n, 3))
    directions = np.tile([1.0, 0.0, 0.0], (1, n, 1))
    return CameraRays(size=(1, n), window=(0, 1, 0, n), origins=origins, directions=directions,
                      t_near=np.full((1, n), t_near), t_far=lengths,
                      hit=np.ones((1, n), bool) if hit is None else np.asarray(hit)[None, :],
                      view_axis=np.array([1.0, 0.0, 0.0]))


def test_homogeneous_world_fog_is_exp_of_kappa_times_length():
    rays = rays_along_x([1.0, 5.0, 20.0], t_near=0.5)
    medium = constant_medium(density=0.2, color=(1.0, 0.5, 0.25))
    x, transmittance, info = x_map_from_cached_rays(rays, [medium], minbound=False)
    kappa = 0.2 * np.array([1.0, 0.5, 0.25])
    expected = np.exp(-np.array([0.5, 4.5, 19.5])[:, None] * kappa)
    assert np.allclose(transmittance[0], expected, rtol=1e-6)
    assert np.allclose(x[0], luminance(expected), rtol=1e-6)
    assert info["media"][0]["method"] == "closed form"


def test_object_media_add_over_their_intervals():
    rays = rays_along_x([10.0, 10.0])
    rays.intervals = {"a": MediumIntervals(np.array([0, 0, 1]), np.array([1.0, 6.0, 2.0]), np.array([3.0, 7.0, 9.0])),
                      "b": MediumIntervals(np.array([1]), np.array([0.0]), np.array([4.0]))}
    media = [constant_medium("a", "mesh", 0.5), constant_medium("b", "mesh", 0.25)]
    _, transmittance, _ = x_map_from_cached_rays(rays, media, minbound=False)
    assert np.allclose(-np.log(transmittance[0, :, 0]), [0.5 * 3.0, 0.5 * 7.0 + 0.25 * 4.0], rtol=1e-6)


def test_marching_integrates_a_varying_density():
    # density = 0.2 x along +x from 0 to L: tau = 0.1 L^2; the midpoint rule is exact on
    # a linear field, so this checks the sample placement and the weights.
    rays = rays_along_x([1.0, 3.0, 7.0])
    _, transmittance, info = x_map_from_cached_rays(rays, [linear_medium(0.2)], minbound=False, samples=8)
    assert np.allclose(-np.log(transmittance[0, :, 1]), 0.1 * np.array([1.0, 9.0, 49.0]), rtol=1e-5)
    assert "midpoint" in info["media"][0]["method"]


def test_minbound_gives_sky_the_smallest_finite_value_exactly():
    x = np.array([[0.3, 0.7, 0.0], [0.9, 0.0, 0.45]], dtype=np.float32)
    sky = np.array([[False, False, True], [False, True, False]])
    bounded, value = apply_minbound(x, sky)
    assert value == pytest.approx(0.3) and np.all(bounded[sky] == np.float32(0.3))
    assert np.array_equal(bounded[~sky], x[~sky])
    assert apply_minbound(x, np.ones_like(sky))[1] is None     # nothing finite: unchanged


@pytest.mark.parametrize("minbound", [True, False])
def test_sky_pixels_with_and_without_minbound(minbound):
    rays = rays_along_x([2.0, 1000.0, 4.0], hit=[True, False, True])
    x, _, info = x_map_from_cached_rays(rays, [constant_medium(density=0.05)], minbound=minbound)
    if minbound:
        assert x[0, 1] == x[0, [0, 2]].min() == np.float32(info["minbound"])
    else:
        assert x[0, 1] == pytest.approx(np.exp(-50.0), abs=1e-12)


def test_no_media_means_x_is_one_with_a_warning():
    rays = rays_along_x([1.0, 2.0], hit=[True, False])
    with pytest.warns(XMapWarning, match="no participating media"):
        x, _, info = x_map_from_cached_rays(rays, [])
    assert np.all(x == 1.0) and info["warnings"]


def test_window_outside_a_border_is_zero():
    rays = rays_along_x([1.0, 2.0])
    rays.size, rays.window = (3, 4), (1, 2, 1, 3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", XMapWarning)
        x, _, _ = x_map_from_cached_rays(rays, [])
    assert x.shape == (3, 4) and x.sum() == 2 and np.all(x[1, 1:3] == 1)


def test_ray_cache_round_trip(tmp_path):
    rays = rays_along_x([1.0, 2.0, 3.0], hit=[True, False, True])
    rays.key = "abc"
    rays.intervals = {"cube#0:0": MediumIntervals(np.array([2], np.int32), np.array([0.5]), np.array([1.5]))}
    path = save_rays(tmp_path / "zcache.npz", rays)
    back = load_rays(path, "abc")
    assert back is not None and back.key == "abc" and back.size == rays.size
    assert np.array_equal(back.t_far, rays.t_far) and np.array_equal(back.hit, rays.hit)
    assert np.array_equal(back.intervals["cube#0:0"].t1, [1.5])
    assert load_rays(path, "another scene") is None
    path.write_bytes(b"not a cache")
    assert load_rays(path, "abc") is None
    assert load_rays(tmp_path / "missing.npz") is None


def test_depth_conversions():
    directions = np.array([[0.0, 0.0, -1.0], [0.6, 0.0, -0.8]])
    axis = np.array([0.0, 0.0, -1.0])
    distance = np.array([2.0, 5.0])
    planar = planar_depth(distance, directions, axis)
    assert np.allclose(planar, [2.0, 4.0])
    assert np.allclose(ray_distance(planar, directions, axis), distance)
    stored = depth_to_exr(np.array([1.5, np.inf]))
    assert stored.dtype == np.float32 and stored[1] == np.float32(SKY_DEPTH)
    assert np.array_equal(depth_from_exr(stored), [1.5, np.inf])


@pytest.mark.parametrize("density", [-0.5, float("nan")])
def test_bad_constant_density_is_refused(density):
    with pytest.raises(InputError, match="density"):
        check_densities(constant_medium(density=density))


def test_a_driven_density_may_dip_below_zero():
    check_densities(linear_medium(-1.0))          # Cycles clamps it at zero; not an error
    rays = rays_along_x([4.0])
    _, transmittance, _ = x_map_from_cached_rays(rays, [linear_medium(-1.0)], minbound=False)
    assert np.all(transmittance == 1.0)


def test_camera_border_and_clip_range():
    camera = CameraModel(kind="PERSP", matrix_world=np.eye(4), width=48, height=40,
                         border=(0.1, 0.2, 0.85, 0.9), clip_start=0.5, clip_end=100.0)
    assert camera.pixel_window() == (4, 32, 4, 40)        # Blender truncates border * size
    _, directions = camera.pixel_rays()
    near, far = camera.clip_range(directions)
    assert np.all(near >= 0.5) and np.all(far >= 100.0) and np.all(far / near == pytest.approx(200.0))
    with pytest.raises(InputError, match="zero area"):
        CameraModel(kind="PERSP", matrix_world=np.eye(4), width=48, height=40,
                    border=(0.5, 0.2, 0.5, 0.9)).pixel_window()
    with pytest.raises(InputError, match="clip start"):
        CameraModel(kind="PERSP", matrix_world=np.eye(4), width=4, height=4, clip_start=5, clip_end=1)


def _lookup3_reference(*keys):
    """Bob Jenkins' lookup3 final mix (hashword for 1..3 words, 4 with one mix) in plain ints."""
    mask = 0xFFFFFFFF

    def rot(x, k):
        return ((x << k) | (x >> (32 - k))) & mask

    a = b = c = (0xDEADBEEF + (len(keys) << 2) + 13) & mask
    words = [k & mask for k in keys]
    if len(words) == 4:
        a, b, c = (a + words[0]) & mask, (b + words[1]) & mask, (c + words[2]) & mask
        for x, y, z, k in (("a", "c", "b", 4), ("b", "a", "c", 6), ("c", "b", "a", 8),
                           ("a", "c", "b", 16), ("b", "a", "c", 19), ("c", "b", "a", 4)):
            v = {"a": a, "b": b, "c": c}
            v[x] = ((v[x] - v[y]) & mask) ^ rot(v[y], k)
            v[y] = (v[y] + v[z]) & mask
            a, b, c = v["a"], v["b"], v["c"]
        words = [0, 0, 0]
        a = (a + keys[3]) & mask
    else:
        for i, word in enumerate(words):
            if i == 0:
                a = (a + word) & mask
            elif i == 1:
                b = (b + word) & mask
            else:
                c = (c + word) & mask
    for x, y, k in (("c", "b", 14), ("a", "c", 11), ("b", "a", 25), ("c", "b", 16),
                    ("a", "c", 4), ("b", "a", 14), ("c", "b", 24)):
        v = {"a": a, "b": b, "c": c}
        v[x] = ((v[x] ^ v[y]) - rot(v[y], k)) & mask
        a, b, c = v["a"], v["b"], v["c"]
    return c


@pytest.mark.parametrize("count", [1, 2, 3, 4])
def test_noise_hash_matches_a_scalar_lookup3(count):
    rng = np.random.default_rng(count)
    keys = rng.integers(-2**31, 2**31, size=(count, 50))
    ours = hash_uint(*keys)
    expected = [_lookup3_reference(*(int(k) & 0xFFFFFFFF for k in column)) for column in keys.T]
    assert ours.tolist() == expected


@pytest.mark.parametrize("count", [1, 2, 3, 4])
def test_perlin_corner_hashes_in_place_are_hash_uint_bit_for_bit(count):
    from itertools import product

    from xsl_render.core.media.cycles_noise import _CornerHash

    rng = np.random.default_rng(10 + count)
    # Cells as Perlin noise has them (int32), with the wrap-around at the extremes.
    cells = [rng.integers(-2**31, 2**31, size=200).astype(np.int32) for _ in range(count)]
    cells[0][:2] = (2**31 - 1, -1)
    corners = _CornerHash(cells)
    for offsets in product((0, 1), repeat=count):
        with np.errstate(over="ignore"):
            expected = hash_uint(*(c + np.int32(o) for c, o in zip(cells, offsets)))
        assert np.array_equal(corners(offsets), expected)


def test_euler_matrix_is_a_rotation():
    m = euler_matrix(np.array([0.3, -1.1, 2.0]))
    assert np.allclose(m @ m.T, np.eye(3), atol=1e-6) and np.linalg.det(m) == pytest.approx(1.0, abs=1e-6)


def test_generated_coordinates_span_the_texture_space():
    from xsl_render.core.media.shader_nodes import generated_coordinates

    context = NodeContext(points=np.array([[1.0, 2.0, 3.0], [3.0, 6.0, 3.5]]),
                          world_to_object=np.eye(4), texspace=((2.0, 4.0, 3.25), (1.0, 2.0, 0.25)))
    assert np.allclose(generated_coordinates(context), [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])


def test_ties_scale_or_replace_the_transmittance():
    transmittance = np.full((2, 3, 3), 0.5, dtype=np.float32)
    passing = np.array([[0.0, 0.5, 1.0], [0.25, 0.0, 0.0]])
    mask = np.zeros((2, 3), dtype=bool)
    mask[1, 2] = True
    measured = (mask, np.full((2, 3, 3), 0.125, dtype=np.float32))
    out = with_ties(transmittance, passing, measured)
    assert out[..., 0].tolist() == [[0.5, 0.25, 0.0], [0.375, 0.5, 0.125]]
    assert transmittance[0, 1, 0] == 0.5                               # not modified
    rays = rays_along_x([1.0, 2.0, 3.0], hit=np.array([True, True, False]))
    x, value = x_from_transmittance(rays, out[:1], minbound=True)
    assert x[0].tolist() == [0.5, 0.25, 0.25] and value == 0.25
