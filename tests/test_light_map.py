"""Eq. 6 (multi-Gaussian light map), its fast evaluation, and the 0-LightMap raster."""
from __future__ import annotations

import math

import numpy as np
import pytest

from xsl_render.core.camera import CameraModel
from xsl_render.core.errors import InputError
from xsl_render.core.maps.light_map import (auto_parameters, eq6_components, glow_kernel,
                                            light_map, multi_gaussian, multi_gaussian_direct,
                                            normalise)
from xsl_render.core.maps.light_raster import Footprint, spot_weight, zero_light_map
from xsl_render.core.maps.scale_space import gaussian_mixture_blur
from xsl_render.core.media.scene_model import LightSource


def single_pixel(shape=(81, 81)) -> np.ndarray:
    image = np.zeros(shape)
    image[shape[0] // 2, shape[1] // 2] = 1.0
    return image


@pytest.mark.parametrize("n", [1, 2, 3])
@pytest.mark.parametrize("sigma_base", [1.0, 2.5])
def test_eq6_against_the_literal_iteration_on_a_single_pixel(n, sigma_base):
    """L_i = L_{i-1} + L_{i-1} * G(sigma_base i), written out by hand with 2-D kernels."""
    image = single_pixel()
    literal = image.copy()
    radius = 40
    y, x = np.mgrid[-radius:radius + 1, -radius:radius + 1]
    for i in range(1, n + 1):
        sigma = sigma_base * i
        kernel = np.exp(-(x * x + y * y) / (2 * sigma * sigma))
        kernel /= kernel.sum()
        padded = np.pad(literal, radius)
        blurred = np.zeros_like(literal)
        for dy in range(-radius, radius + 1):       # direct 2-D convolution, no FFT, no scipy
            for dx in range(-radius, radius + 1):
                w = kernel[dy + radius, dx + radius]
                if w > 1e-12:
                    blurred += w * padded[radius - dy:radius - dy + image.shape[0],
                                          radius - dx:radius - dx + image.shape[1]]
        literal = literal + blurred
    fast = multi_gaussian(image, n, sigma_base, scale=1.0)
    np.testing.assert_allclose(fast, literal, atol=2e-3 * literal.max())
    assert fast.sum() == pytest.approx(2.0 ** n, rel=1e-3)     # each step doubles the mass


def test_eq6_components_are_the_expanded_product():
    sigmas, counts = eq6_components(2, 3.0)
    np.testing.assert_allclose(sigmas, [0, 3, 6, 3 * math.sqrt(5)])
    np.testing.assert_array_equal(counts, [1, 1, 1, 1])
    sigmas, counts = eq6_components(20, 10.0)
    assert counts.sum() == 2 ** 20
    assert sigmas.max() == pytest.approx(10 * math.sqrt(20 * 21 * 41 / 6))


# At 128 px the sigmas shrink by 4; all stay >= 1 px, where scipy's sampled kernels are exact.
@pytest.mark.parametrize("n, sigma_base", [(4, 4.0), (8, 4.0), (12, 6.0)])
def test_fast_eq6_matches_scipy_iteration(n, sigma_base):
    rng = np.random.default_rng(n)
    image = np.zeros((72, 128))
    for _ in range(5):
        r, c = rng.integers(5, 67), rng.integers(5, 123)
        image[r - 2:r + 2, c - 2:c + 2] = rng.uniform(0.5, 3)
    scale = 128 / 512
    fast = multi_gaussian(image, n, sigma_base)
    direct = multi_gaussian_direct(image, n, sigma_base, scale=scale)
    np.testing.assert_allclose(fast, direct, atol=5e-3 * direct.max())


@pytest.mark.parametrize("sigma", [1.0, 3.0, 9.0, 40.0, 150.0])
def test_scale_space_blur_matches_a_direct_blur(sigma):
    from scipy import ndimage

    image = np.zeros((60, 90))
    image[20:24, 30:33] = 1.0
    image[50, 80] = 4.0
    margin = int(4 * sigma) + 2
    direct = ndimage.gaussian_filter(np.pad(image, margin), sigma, mode="constant")[margin:-margin, margin:-margin]
    fast = gaussian_mixture_blur(image, [sigma], [1.0])
    np.testing.assert_allclose(fast, direct, atol=2e-3 * direct.max())


@pytest.mark.parametrize("sigma", [0.2, 0.45, 0.7])
def test_narrow_blurs_add_exactly_their_variance(sigma):
    """Below one pixel a sampled Gaussian loses variance; ours must not."""
    impulse = single_pixel((21, 21))
    out = gaussian_mixture_blur(impulse, [sigma], [1.0])
    offsets = np.arange(21) - 10
    variance_rows = float((out.sum(axis=1) * offsets ** 2).sum())
    assert out.sum() == pytest.approx(1.0) and variance_rows == pytest.approx(sigma ** 2, rel=1e-6)


def point_lamp(name="lamp", row=72, col=128, mass=1.0, tau=0.5):
    return Footprint(name, row, col, np.full((1, 1), mass), tau)


def test_glow_grows_with_n_and_sigma_base():
    def glow_area(n, sigma_base):
        l_map, _ = light_map([point_lamp()], (144, 256), {"lamp": (n, sigma_base)})
        return int((l_map > 0.1).sum())
    areas_n = [glow_area(n, 4.0) for n in (2, 4, 8, 12)]
    areas_sigma = [glow_area(8, s) for s in (1.0, 2.0, 4.0, 8.0)]
    assert areas_n == sorted(areas_n) and areas_n[0] < areas_n[-1]
    assert areas_sigma == sorted(areas_sigma) and areas_sigma[0] < areas_sigma[-1]


def test_each_light_glows_at_its_perceived_brightness():
    """Cube root of the share of light: a lamp with 1/8 of the brightest's glows at 1/2."""
    lamps = [point_lamp("bright", 40, 60, 8.0), point_lamp("dim", 40, 200, 1.0)]
    l_map, report = light_map(lamps, (80, 256), {"bright": (8, 4.0), "dim": (8, 4.0)})
    assert [r["brightness"] for r in report] == pytest.approx([1.0, 0.5])
    # The cores clip at 1; around them each glow is scaled to its lamp's brightness.
    assert l_map[40, 60] == l_map[40, 200] == 1.0
    for offset in (1, 5, 10):
        assert l_map[40, 200 + offset] / l_map[40, 60 + offset] == pytest.approx(0.5, rel=0.02)
    assert l_map[40, 65] > 0.5          # a point lamp keeps its glow: 5 px away, over half


@pytest.mark.parametrize("n, sigma_base", [(3, 2.0), (8, 4.0), (12, 6.0)])
def test_analytic_glow_peak_matches_the_spread_map(n, sigma_base):
    image = single_pixel((121, 121))
    spread = multi_gaussian(image, n, sigma_base, scale=1.0) - image
    assert glow_kernel(np.array(0.0), n, sigma_base) == pytest.approx(spread[60, 60], rel=0.02)
    assert glow_kernel(np.array(10.0), n, sigma_base) == pytest.approx(spread[60, 70], rel=0.02)


def test_sigmas_scale_with_resolution():
    small, large = np.zeros((36, 64)), np.zeros((144, 256))
    small[18, 32] = 1.0
    large[72:76, 128:132] = 1.0 / 16
    a = normalise(multi_gaussian(small, 6, 4.0))
    b = normalise(multi_gaussian(large, 6, 4.0))
    b_small = b.reshape(36, 4, 64, 4).mean(axis=(1, 3))
    assert np.abs(a - b_small / b_small.max()).max() < 0.1


def test_normalise_empty_map_is_zero_not_nan():
    out = normalise(np.zeros((4, 4)))
    assert not out.any() and np.isfinite(out).all()


@pytest.mark.parametrize("n, sigma_base", [(-1, 4.0), (3, 0.0), (3, -2.0), (3, float("nan"))])
def test_bad_parameters_name_the_option(n, sigma_base):
    with pytest.raises(InputError, match="light_n|light_sigma_base"):
        multi_gaussian(np.zeros((8, 8)), n, sigma_base)


def test_auto_parameters_thicken_with_optical_depth():
    values = [auto_parameters(tau) for tau in (0.0, 0.2, 1.0, 3.0, 20.0)]
    assert values[0] == (4, 1.0)
    assert [v[0] for v in values] == sorted(v[0] for v in values)
    assert [v[1] for v in values] == sorted(v[1] for v in values)
    assert auto_parameters(0.8) == (8, pytest.approx(3.5, abs=0.05))    # the paper's thin road
    assert values[-1][0] == 20 and values[-1][1] == pytest.approx(10.0, abs=0.2)


# --- the 0-LightMap -----------------------------------------------------------------

def camera_at_origin(width=64, height=36) -> CameraModel:
    """Camera at the origin looking down -Z (Blender's convention)."""
    return CameraModel(kind="PERSP", matrix_world=np.eye(4), width=width, height=height)


def lamp(name="Lamp", location=(0.0, 0.0, -10.0), size=0.3, energy=1000.0, kind="POINT", **kw):
    return LightSource(name=name, kind=kind, location=location, direction=kw.pop("direction", (0, 0, 1)),
                       size=size, color=(1.0, 1.0, 1.0), energy=energy, **kw)


def no_fog(points):
    return np.ones(len(points))


def test_a_point_light_is_a_disc_at_its_projection():
    cam = camera_at_origin()
    distance = np.full((36, 64), np.inf)
    l0, report = zero_light_map(cam, [lamp()], distance, no_fog)
    assert report[0].drawn
    rows, cols = np.nonzero(l0)
    assert rows.mean() == pytest.approx(18.0, abs=0.6) and cols.mean() == pytest.approx(32.0, abs=0.6)
    # radius 0.3 at distance 10 with 50 mm / 36 mm: 0.3 / (0.72 / 64 * 10) = 2.67 px
    assert report[0].pixels == pytest.approx(math.pi * 2.667 ** 2, rel=0.05)


def test_a_light_behind_a_wall_is_not_drawn_and_a_half_hidden_one_is_clipped():
    cam = camera_at_origin()
    wall = np.full((36, 64), 5.0)            # a wall 5 units away covers everything
    l0, report = zero_light_map(cam, [lamp()], wall, no_fog)
    assert not l0.any() and report[0].reason == "hidden behind geometry"
    half = np.full((36, 64), np.inf)
    half[:, :32] = 5.0                       # the wall covers the left half of the frame
    l0, report = zero_light_map(cam, [lamp()], half, no_fog)
    assert l0[:, :32].sum() == 0 and l0[:, 32:].sum() > 0
    assert 0.3 < report[0].visible_fraction < 0.7 and "clipped" in report[0].reason


def test_the_fog_dims_a_distant_lamp():
    cam = camera_at_origin()
    distance = np.full((36, 64), np.inf)
    near = lamp("near", location=(-2.0, 0.0, -10.0), size=0.0)
    far = lamp("far", location=(2.0, 0.0, -10.0), size=0.0)
    fog = lambda points: np.where(points[:, 0] > 0, 0.1, 0.9)   # far one behind thick fog
    l0, report = zero_light_map(cam, [near, far], distance, fog)
    assert l0[:, :32].sum() == pytest.approx(9 * l0[:, 32:].sum(), rel=1e-3)
    assert report[1].optical_depth == pytest.approx(-math.log(0.1))


@pytest.mark.parametrize("direction, expected", [((0, 0, 1), 1.0), ((0, 0, -1), 0.0), ((1, 0, 0), 0.0)])
def test_spot_lights_count_only_when_the_camera_is_in_the_cone(direction, expected):
    spot = lamp(kind="SPOT", direction=direction, spot_size=math.radians(60), spot_blend=0.2)
    assert spot_weight(spot, np.zeros(3)) == pytest.approx(expected)


def test_spot_cone_edge_is_smooth():
    eye = np.zeros(3)
    spot = lamp(kind="SPOT", location=(0, 0, -10), spot_size=math.radians(60), spot_blend=0.5)
    weights = []
    for angle in (0, 20, 25, 28, 29.5, 31):
        a = math.radians(angle)
        spot.direction = (math.sin(a), 0.0, math.cos(a))
        weights.append(spot_weight(spot, eye))
    assert weights[0] == 1.0 and weights[-1] == 0.0
    assert weights == sorted(weights, reverse=True) and 0 < weights[3] < 1


def test_area_light_seen_from_behind_is_not_drawn():
    cam = camera_at_origin()
    distance = np.full((36, 64), np.inf)
    front = lamp(kind="AREA", size=1.0, size_y=1.0, shape="SQUARE", direction=(0, 0, 1))
    back = lamp(kind="AREA", size=1.0, size_y=1.0, shape="SQUARE", direction=(0, 0, -1))
    assert zero_light_map(cam, [front], distance, no_fog)[0].any()
    assert not zero_light_map(cam, [back], distance, no_fog)[0].any()


def test_emission_image_adds_meshes_dimmed_by_their_transmittance():
    cam = camera_at_origin(16, 9)
    emission = np.zeros((9, 16, 3))
    emission[4, 8] = (2.0, 2.0, 2.0)
    x_map = np.full((9, 16), 0.25)
    l0, _ = zero_light_map(cam, [], np.full((9, 16), np.inf), no_fog, emission, x_map)
    # radiance 2, transmittance 0.25, times the solid angle of one pixel
    expected = 0.5 * (0.72 / 16) * (0.405 / 9)
    assert l0[4, 8] == pytest.approx(expected, rel=1e-5) and l0.sum() == pytest.approx(expected, rel=1e-5)


@pytest.mark.parametrize("size", [0.0, 0.05, 0.6])
def test_a_lamp_weighs_its_irradiance_whatever_its_size(size):
    """I / d^2 = 1000 / (4 pi) / 100 lands in the map whether the lamp covers 0.01 or 30 px."""
    cam = camera_at_origin()
    l0, report = zero_light_map(cam, [lamp(size=size)], np.full((36, 64), np.inf), no_fog)
    assert l0.sum() == pytest.approx(1000 / (4 * math.pi) / 100, rel=1e-5)
    assert report[0].irradiance == pytest.approx(1000 / (4 * math.pi) / 100)
