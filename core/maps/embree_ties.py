"""Which of Cycles' samples pass a volume face lying on a surface: Embree's arithmetic replayed.

Where a mesh volume's face lies on a surface (a fog box resting on the floor), a sample
passes only where the two faces meet it at the very same float: Cycles restarts a ray leaving
the volume at the next float after the hit and so skips a surface at the same distance. The
roundings of Embree's robust triangle test (single precision, vertices relative to the ray's
origin, the near-clip start rounded per sample) decide which samples tie: ``f``, computed
here per pixel. Which face Embree reports first on an exact tie depends on its tree: ``w``,
measured by a few probe renders (``addon.maps.ties``). The passing share is ``w * f``; how
well the replay agrees with Embree: docs/design.md, "The X map's oracle"."""
from __future__ import annotations

import numpy as np

from .camera_rays import RayModel

_F32 = np.float32
#: The oracle's pixel filter (``addon.maps.transmittance_oracle``): Blackman-Harris this
#: wide, in pixels, so all samples of a pixel go through (nearly) its centre.
ORACLE_FILTER_WIDTH = 0.01


def fma32(a, b, c) -> np.ndarray:
    """Single-precision fused multiply-add: the product exact in double, one rounding of
    the sum to double and one to single (differs from one rounding in rare halfway cases)."""
    return (np.asarray(a, np.float64) * np.asarray(b, np.float64)
            + np.asarray(c, np.float64)).astype(_F32)


def cycles_world_vertices(local: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """World-space vertices (V, 3) float32 as Cycles makes them for a static BVH
    (``Mesh::apply_transform``, ``transform_point``): translation, then + z, y, x times
    the matrix's columns, each step rounded to single precision."""
    m = np.asarray(matrix, dtype=np.float64).astype(_F32)
    p = np.asarray(local, dtype=np.float64).astype(_F32)
    out = np.broadcast_to(m[:3, 3], p.shape).astype(_F32)
    for axis in (2, 1, 0):
        out = (out + (p[:, axis:axis + 1] * m[:3, axis]).astype(_F32)).astype(_F32)
    return out


def _cross_stable(a, b, c):
    """Embree's ``stable_triangle_normal`` of three edges, each a list of x, y, z arrays."""
    ab = (a[2] * b[1], a[0] * b[2], a[1] * b[0])
    bc = (b[2] * c[1], b[0] * c[2], b[1] * c[0])
    cross_ab = (fma32(a[1], b[2], -ab[0]), fma32(a[2], b[0], -ab[1]), fma32(a[0], b[1], -ab[2]))
    cross_bc = (fma32(b[1], c[2], -bc[0]), fma32(b[2], c[0], -bc[1]), fma32(b[0], c[1], -bc[2]))
    return [np.where(np.abs(ab[k]) < np.abs(bc[k]), cross_ab[k], cross_bc[k]) for k in range(3)]


def _dot(a, b):
    """Embree's ``dot``: madd(a.x, b.x, madd(a.y, b.y, a.z * b.z))."""
    return fma32(a[0], b[0], fma32(a[1], b[1], (a[2] * b[2]).astype(_F32)))


def _components(vectors: np.ndarray) -> list[np.ndarray]:
    """x, y, z of (..., 3) vectors as float32 arrays."""
    vectors = np.asarray(vectors)
    return [np.ascontiguousarray(vectors[..., k], dtype=_F32) for k in range(3)]


def _intermediates(o, d, tri):
    """The values Embree's robust test computes on the way to ``t``: ``o``, ``d`` the
    rays' origin and direction and ``tri`` three vertices, each vector a list of x, y, z
    float32 arrays that broadcast together. Returns (vectors: vertices relative to the
    origin, edges, normal; den; T; t)."""
    v0, v1, v2 = ([(tri[k][i] - o[i]).astype(_F32) for i in range(3)] for k in range(3))
    e0 = [v2[i] - v0[i] for i in range(3)]
    e1 = [v0[i] - v1[i] for i in range(3)]
    e2 = [v1[i] - v2[i] for i in range(3)]
    normal = _cross_stable(e0, e1, e2)
    den = (_F32(2) * _dot(normal, d)).astype(_F32)
    big_t = (_F32(2) * _dot(v0, normal)).astype(_F32)
    with np.errstate(divide="ignore", invalid="ignore"):
        rcp = (_F32(1) / den).astype(_F32)
        rcp = fma32(rcp, fma32(-den, rcp, _F32(1)), rcp)     # Embree's Newton step
        t = (rcp * big_t).astype(_F32)
    return (v0, v1, v2, e0, e1, e2, normal), den, big_t, t


def embree_distance(origins: np.ndarray, directions: np.ndarray,
                    triangles: np.ndarray) -> np.ndarray:
    """Distance ``t`` at which Embree's robust test meets each ray's triangle.

    Parameters
    ----------
    origins, directions : (..., 3) arrays
        The rays as Cycles hands them to Embree (single precision; directions unit length).
    triangles : (..., 3, 3) array
        Each ray's triangle (broadcasting against the rays): its three vertices in Cycles'
        order, world space, float32.

    Returns
    -------
    (...) float32: the distance along the ray (inf or NaN where the ray is parallel).
    The edge tests are left out: the caller knows the ray meets the triangle.
    """
    tri = [_components(np.asarray(triangles)[..., k, :]) for k in range(3)]
    return _intermediates(_components(origins), _components(directions), tri)[3]


def exact_ties(origins: np.ndarray, directions: np.ndarray, first: np.ndarray,
               second: np.ndarray) -> np.ndarray:
    """(...) bool: Embree meets the two triangles (..., 3, 3) at the same float distance."""
    return embree_distance(origins, directions, first) == embree_distance(origins, directions, second)


def band_keys(origins: np.ndarray, directions: np.ndarray, first: np.ndarray,
              second: np.ndarray) -> np.ndarray:
    """(N,) int64 hash of the binary exponents of everything Embree rounds on the way to
    both distances (rays (N, 3), triangles (N, 3, 3)): rays with the same key round at
    the same scales, so their fraction of exact ties changes only slowly between them; it
    jumps where a key changes."""
    o, d = _components(origins), _components(directions)
    parts = [*o, *d]
    for triangles in (first, second):
        tri = [_components(np.asarray(triangles)[:, k, :]) for k in range(3)]
        vectors, den, big_t, t = _intermediates(o, d, tri)
        parts += [c for vector in vectors for c in vector] + [den, big_t, t]
    key = np.zeros(len(origins), dtype=np.int64)
    for part in parts:
        exponent = np.frexp(part)[1].astype(np.int64) * 2 + np.signbit(part)
        key = key * np.int64(1_000_003) + exponent
    return key


def _filter_table(size: int = 4096) -> np.ndarray:
    """The inverse of the Blackman-Harris filter's integral over [-0.5, 0.5], tabulated."""
    v = np.linspace(-0.5, 0.5, 1025)
    phase = 2.0 * np.pi * (v + 0.5)
    weight = (0.35875 - 0.48829 * np.cos(phase) + 0.14128 * np.cos(2 * phase)
              - 0.01168 * np.cos(3 * phase))
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (weight[1:] + weight[:-1]))])
    return np.interp((np.arange(size) + 0.5) / size, cdf / cdf[-1], v)


_FILTER_TABLE = _filter_table()


def blackman_harris_offsets(rng: np.random.Generator, shape, width: float = ORACLE_FILTER_WIDTH,
                            ) -> np.ndarray:
    """Sub-pixel offsets (``shape``) distributed as Cycles' Blackman-Harris pixel filter of
    ``width`` pixels (importance sampled through the inverse of the filter's integral, as
    Cycles' filter table does)."""
    if width == 0:
        return np.zeros(shape)
    return _FILTER_TABLE[rng.integers(0, len(_FILTER_TABLE), shape)] * width


def camera_samples(model: RayModel, rows: np.ndarray, cols: np.ndarray, view_axis: np.ndarray,
                   clip_start: float, per_pixel: int, rng: np.random.Generator,
                   width: float = ORACLE_FILTER_WIDTH) -> tuple[list, list]:
    """Rays of a perspective camera as Cycles samples them, ``per_pixel`` for each pixel.

    Parameters
    ----------
    model : RayModel
        The camera's rays at any pixel position (``core.maps.camera_rays.fit_ray_model``);
        the origin is the eye.
    rows, cols : (P,) arrays
        Pixels (window coordinates, their centres at integer positions).
    view_axis : (3,) array
        Unit vector the camera looks along.
    clip_start : float
        The camera's near clip distance.
    per_pixel : int
        Samples per pixel, jittered by the oracle's pixel filter (``width`` 0: centres).

    Returns
    -------
    origins, directions : lists of x, y, z float32 arrays (P, per_pixel)
        Each direction rounded to single precision; each origin moved onto the near clip
        plane as ``camera_sample_perspective`` does (``P += clip_start / cos * D``).
    """
    shape = (len(rows), per_pixel)
    y = np.asarray(rows, np.float64)[:, None] + blackman_harris_offsets(rng, shape, width)
    x = np.asarray(cols, np.float64)[:, None] + blackman_harris_offsets(rng, shape, width)
    plane = [model.plane[0, k] + x * model.plane[1, k] + y * model.plane[2, k] for k in range(3)]
    inverse = 1.0 / np.sqrt(plane[0] ** 2 + plane[1] ** 2 + plane[2] ** 2)
    d = [(c * inverse).astype(_F32) for c in plane]
    axis = np.asarray(view_axis, np.float64)
    cos = (d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2]).astype(_F32)
    near = (_F32(clip_start) * (_F32(1) / cos)).astype(_F32)
    eye = np.asarray(model.origin[0], np.float64).astype(_F32)
    o = [(eye[k] + (near * d[k]).astype(_F32)).astype(_F32) for k in range(3)]
    return o, d


#: Rays replayed at once (bounds the temporaries, not the result).
_CHUNK = 1 << 17
#: Pixels pool their rays into one estimate only with pixels of the same key and pair
#: inside a square cell holding about this many rays (one pixel when it has them itself),
#: and at most ``pool_side`` pixels wide: the fraction drifts with the roundings'
#: mantissas too, so a cell must stay small in angle (measured: a 64-pixel frame pools
#: 2x2 cells well, 8x8 cells lose a third of the gain; on 384x216, 8 to 64 pixels wide
#: cells all do).
POOL_RAYS = 4096


def exact_tie_fractions(model: RayModel, rows: np.ndarray, cols: np.ndarray,
                        view_axis: np.ndarray, clip_start: float, first: np.ndarray,
                        second: np.ndarray, pair: np.ndarray, per_pixel: int,
                        rng: np.random.Generator, pool_side: int = 1) -> np.ndarray:
    """Per pixel, the fraction of the oracle's samples that meet two coincident triangles
    at the very same float distance (those a tie can let through).

    Each pixel gets ``per_pixel`` rays as Cycles samples them (:func:`camera_samples`).
    The fraction moves slowly between pixels whose centre rays round at the same scales
    (:func:`band_keys`) and jumps between others, so pixels with few rays pool them with
    the pixels of the same key and pair of triangles in a square cell of about
    ``POOL_RAYS`` rays (at most ``pool_side`` pixels a side).

    Parameters
    ----------
    model : RayModel
        The camera's rays at any pixel position.
    rows, cols : (P,) arrays
        The pixels, window coordinates.
    view_axis, clip_start
        The camera's view direction and near clip distance.
    first, second : (P, 3, 3) float32 arrays
        Each pixel's two triangles, vertices as Cycles holds them.
    pair : (P,) int array
        Which pair of triangles each pixel sees (pixels of different pairs never pool).
    per_pixel : int
        Rays replayed per pixel.
    pool_side : int
        Widest cell, in pixels, whose pixels may pool their rays (1: none do).

    Returns
    -------
    (P,) float64 in [0, 1].
    """
    count = len(rows)
    if not count:
        return np.zeros(0)
    ties = np.zeros(count)
    step = max(1, _CHUNK // per_pixel)
    for start in range(0, count, step):
        part = slice(start, start + step)
        o, d = camera_samples(model, rows[part], cols[part], view_axis, clip_start, per_pixel, rng)
        t = [_intermediates(o, d, [_components(tri[part, k, None, :]) for k in range(3)])[3]
             for tri in (first, second)]
        ties[part] = (t[0] == t[1]).sum(axis=1)
    side = min(int(round(np.sqrt(POOL_RAYS / per_pixel))), int(pool_side))
    if side <= 1:
        return ties / per_pixel
    o, d = camera_samples(model, rows, cols, view_axis, clip_start, 1, rng, width=0.0)
    key = band_keys(np.stack(o, -1)[:, 0], np.stack(d, -1)[:, 0], first, second)
    key = key * np.int64(1_000_003) + np.asarray(pair, np.int64)
    key = key * np.int64(1_000_003) + (rows // side).astype(np.int64) * 65_537 + cols // side
    _, group = np.unique(key, return_inverse=True)
    return (np.bincount(group, weights=ties) / (np.bincount(group) * per_pixel))[group]
