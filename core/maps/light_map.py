"""The light map of section 4.4: a 0-LightMap spread by the multi-Gaussian filter of eq. 6,
``L_i = L_{i-1} + L_{i-1} * G(sigma_base * i)``, i = 1..n.

Convolution is linear, so ``L_n`` is one Gaussian per subset of {1..n} (variances add):
``multi_gaussian`` applies the whole sum in one pass over a scale space,
``multi_gaussian_direct`` is the literal iteration, kept as the reference. Sigmas are in
pixels at 512 px on the longer side. Each light's glow peaks at its perceived brightness
relative to the brightest (the cube root of its share of light, CIE lightness), so one
bright lamp does not flatten every other light's glow."""
from __future__ import annotations

import numpy as np
from scipy import ndimage

from ..errors import SettingError
from ..option_table import MAX_N, MAX_SIGMA_BASE
from .scale_space import gaussian_mixture_blur

#: Sigmas are specified for this many pixels on the longer side (the paper's 512 px).
REFERENCE_SIZE = 512


def check_parameters(n: int, sigma_base: float) -> None:
    if not isinstance(n, (int, np.integer)) or not 0 <= n <= MAX_N:
        raise SettingError(f"{{light_n.name}} must be a whole number from 0 to {MAX_N}, "
                           "got {light_n.value}", light_n=n)
    if not np.isfinite(sigma_base) or not 0 < sigma_base <= MAX_SIGMA_BASE:
        raise SettingError(f"{{light_sigma_base.name}} must be > 0 and at most "
                           f"{MAX_SIGMA_BASE:g}, got {{light_sigma_base.value}}",
                           light_sigma_base=sigma_base)


def resolution_scale(shape: tuple[int, int]) -> float:
    """Factor from sigmas at 512 px to pixels of an image of this shape."""
    return max(shape[0], shape[1]) / REFERENCE_SIZE


def eq6_components(n: int, sigma_base: float) -> tuple[np.ndarray, np.ndarray]:
    """The Gaussians whose sum is prod_{i=1..n} (delta + G(sigma_base i)).

    Returns (sigmas, counts): ``counts[k]`` subsets of {1..n} have sum of squares
    ``(sigmas[k] / sigma_base)^2``; sigma 0 (the empty subset) is the identity.
    """
    check_parameters(n, sigma_base)
    total = n * (n + 1) * (2 * n + 1) // 6
    counts = np.zeros(total + 1, dtype=np.float64)   # float: 2^n overflows int64 past n = 62
    counts[0] = 1.0
    for i in range(1, n + 1):
        counts[i * i:] = counts[i * i:] + counts[:total + 1 - i * i].copy()
    variance_units = np.nonzero(counts)[0]
    return sigma_base * np.sqrt(variance_units.astype(np.float64)), counts[variance_units]


def multi_gaussian(zero_light_map: np.ndarray, n: int, sigma_base: float,
                   scale: float | None = None) -> np.ndarray:
    """L_n of eq. 6 (not normalised), for sigmas given at 512 px.

    ``scale`` converts them to pixels of this image (default: ``resolution_scale``).
    Convolution is on the infinite plane: zero outside the frame, nothing reflected.
    """
    image = np.asarray(zero_light_map, dtype=np.float64)
    scale = resolution_scale(image.shape) if scale is None else scale
    sigmas, counts = eq6_components(n, sigma_base)
    return gaussian_mixture_blur(image, sigmas * scale, counts)


#: Perceived brightness ~ luminance ** (1/3) (CIE 1976 lightness).
BRIGHTNESS_EXPONENT = 1.0 / 3.0


def glow_kernel(radius: np.ndarray, n: int, sigma_base: float, scale: float = 1.0) -> np.ndarray:
    """Value at ``radius`` pixels of prod_i (delta + G(sigma_base i)) minus its delta: the
    glow a unit of light spreads, as the sum of the expanded Gaussians."""
    sigmas, counts = eq6_components(n, sigma_base)
    radius = np.asarray(radius, dtype=np.float64)
    out = np.zeros_like(radius)
    for sigma, count in zip(sigmas * scale, counts):
        if sigma > 0:
            out += count / (2 * np.pi * sigma * sigma) * np.exp(-radius * radius / (2 * sigma * sigma))
    return out


def light_map(footprints, shape: tuple[int, int], parameters: dict[str, tuple[int, float]],
              exponent: float = BRIGHTNESS_EXPONENT) -> tuple[np.ndarray, list[dict]]:
    """The L map in [0, 1] from the lights' footprints (``core.maps.light_raster.Footprint``).

    ``parameters`` maps each footprint's name to its (n, sigma_base). Each light's glow is
    scaled to peak at (its light / the brightest's) ** ``exponent``; lights that share
    (n, sigma_base) are spread by one eq. 6 pass together. Returns the map and, per light,
    its brightness and parameters.
    """
    lit = [f for f in footprints if f.mass > 0]
    if not lit:
        return np.zeros(shape, dtype=np.float32), []
    scale = resolution_scale(shape)
    brightest = max(f.mass for f in lit)
    groups: dict[tuple[int, float], np.ndarray] = {}
    report = []
    for footprint in lit:
        n, sigma_base = parameters[footprint.name]
        check_parameters(n, sigma_base)
        brightness = (footprint.mass / brightest) ** exponent
        h, w = footprint.values.shape
        rows, cols = np.mgrid[0:h, 0:w]
        weights = footprint.values / footprint.mass
        centre = ((rows * weights).sum(), (cols * weights).sum())
        radius = np.hypot(rows - centre[0], cols - centre[1])
        peak = float((footprint.values * glow_kernel(radius, n, sigma_base, scale)).sum())
        if peak <= 0:                              # n = 0: no glow, the light itself
            peak = float(footprint.values.max())
        key = (int(n), float(sigma_base))
        groups[key] = footprint.place(shape, brightness / peak, out=groups.get(key))
        report.append({"light": footprint.name, "n": int(n), "sigma_base": float(sigma_base),
                       "brightness": brightness, "optical_depth": footprint.optical_depth})
    total = np.zeros(shape, dtype=np.float64)
    for (n, sigma_base), seeds in groups.items():
        total += multi_gaussian(seeds, n, sigma_base, scale)
    return np.clip(total, 0.0, 1.0).astype(np.float32), report


def multi_gaussian_direct(zero_light_map: np.ndarray, n: int, sigma_base: float,
                          scale: float = 1.0, margin: int | None = None) -> np.ndarray:
    """Eq. 6 iterated literally, with scipy's Gaussian filter on a zero-padded canvas.

    Slow for wide sigmas; the reference ``multi_gaussian`` is tested against.
    """
    check_parameters(n, sigma_base)
    image = np.asarray(zero_light_map, dtype=np.float64)
    reach = int(np.ceil(4 * sigma_base * scale * np.sqrt(n * (n + 1) * (2 * n + 1) / 6))) + 1
    margin = reach if margin is None else margin
    level = np.pad(image, margin)
    for i in range(1, n + 1):
        level = level + ndimage.gaussian_filter(level, sigma_base * i * scale, mode="constant", truncate=4.0)
    return level[margin:margin + image.shape[0], margin:margin + image.shape[1]]


def normalise(light_map: np.ndarray) -> np.ndarray:
    """Scale to [0, 1] by the maximum; an all-zero map stays zero (no NaN)."""
    peak = float(np.max(light_map)) if light_map.size else 0.0
    if peak <= 0 or not np.isfinite(peak):
        return np.zeros_like(light_map, dtype=np.float32)
    return np.clip(light_map / peak, 0.0, 1.0).astype(np.float32)


def auto_parameters(optical_depth: float) -> tuple[int, float]:
    """(n, sigma_base) from the optical depth tau between the camera and a light.

    The paper: n 4-8 and sigma_base up to 4 for thin media, up to n = 20 and sigma_base = 10
    for thick ones, and (8, 4) for the "thin" foggy road of its Fig. 5c. We map
    1 - exp(-tau / 2.5) linearly onto those ranges: tau -> 0 gives (4, 1); our road's
    headlights (tau about 0.8) get (8, 3.5), its farthest lamp (tau 2.4) (14, 6.7); a
    light barely seen through thick smoke (tau >= 8) nearly (20, 10). Gentler slopes made
    far lamps' glows much wider than Cycles renders them.
    """
    thickness = 1.0 - float(np.exp(-max(float(optical_depth), 0.0) / 2.5))
    return int(round(4 + 16 * thickness)), round(1.0 + 9.0 * thickness, 1)
