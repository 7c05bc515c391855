"""Cycles' Perlin noise and its fractal variants, vectorised in numpy.

A port of Cycles' ``kernel/svm/noise.h``, ``fractal_noise.h`` and ``noisetex.h`` (and the
Jenkins lookup3 hash of ``util/hash.h`` they use), so a Noise Texture node driving a
volume's density evaluates here to what Cycles renders. Cycles computes in float32; so
does this port (the hash needs the same integer lattice cells, and float32 keeps the last
digits in step with the renderer).

Every function takes arrays of points (the last axis holds the 1 to 4 coordinates) and
returns one value per point. Parameters may be scalars or arrays broadcastable to the
points (a Detail socket driven by another texture varies per point).
"""
from __future__ import annotations

import numpy as np

F32 = np.float32
NOISE_TYPES = ("FBM", "MULTIFRACTAL", "HYBRID_MULTIFRACTAL", "RIDGED_MULTIFRACTAL",
               "HETERO_TERRAIN")
# Output ranges of raw Perlin noise per dimension, measured by the OSL authors.
_NOISE_SCALE = {1: F32(0.25), 2: F32(0.6616), 3: F32(0.9820), 4: F32(0.8344)}


# ---------------------------------------------------------------------------------------
# Jenkins lookup3 hash (uint32 arithmetic wraps in numpy as it does in C)

def _rot_into(x, k, out, spare):
    """``out`` = rot(x, k), using ``spare``."""
    np.left_shift(x, np.uint32(k), out=out)
    np.right_shift(x, np.uint32(32 - k), out=spare)
    np.bitwise_or(out, spare, out=out)


def _final(a, b, c, scratch):
    """lookup3's ``final``, in place in ``a``, ``b``, ``c`` (its result in ``c``); ``scratch``: two
    arrays of their shape."""
    rot, spare = scratch
    for x, y, k in ((c, b, 14), (a, c, 11), (b, a, 25), (c, b, 16), (a, c, 4), (b, a, 14), (c, b, 24)):
        np.bitwise_xor(x, y, out=x)
        _rot_into(y, k, rot, spare)
        np.subtract(x, rot, out=x)


def _mix(a, b, c, scratch):
    """lookup3's ``mix``, in place."""
    rot, spare = scratch
    for x, y, z, k in ((a, b, c, 4), (b, c, a, 6), (c, a, b, 8), (a, b, c, 16), (b, c, a, 19),
                       (c, a, b, 4)):
        # x = (x - z) ^ rot(z, k); z = z + y  (lookup3's mix, line pair by line pair)
        np.subtract(x, z, out=x)
        _rot_into(z, k, rot, spare)
        np.bitwise_xor(x, rot, out=x)
        np.add(z, y, out=z)


def _u32(x):
    x = np.asarray(x)
    if x.dtype == np.uint32:
        return x
    return x.astype(np.int64).astype(np.uint32)


def _hash_init(n: int) -> np.uint32:
    """lookup3's starting value of a, b and c for ``n`` 32-bit keys."""
    return np.uint32((0xDEADBEEF + (n << 2) + 13) & 0xFFFFFFFF)


def hash_uint(*keys) -> np.ndarray:
    """Cycles' ``hash_uint``..``hash_uint4`` of 1 to 4 unsigned integer arrays."""
    n = len(keys)
    if not 1 <= n <= 4:
        raise ValueError("hash_uint takes 1 to 4 keys")
    keys = [_u32(k) for k in keys]
    with np.errstate(over="ignore"):
        init = _hash_init(n)
        shape = np.broadcast_shapes(*(k.shape for k in keys))
        a, b, c = (np.full(shape, init, dtype=np.uint32) for _ in range(3))
        for target, key in zip((a, b, c), keys[:3]):
            np.add(target, key, out=target)
        scratch = (np.empty(shape, np.uint32), np.empty(shape, np.uint32))
        if n == 4:
            _mix(a, b, c, scratch)
            np.add(a, keys[3], out=a)
        _final(a, b, c, scratch)
        return c


def hash_float_to_float(*values) -> np.ndarray:
    """Cycles' ``hash_float*_to_float``: the bits of float32 values hashed into [0, 1]."""
    keys = [np.asarray(v, dtype=F32).view(np.uint32) for v in values]
    return hash_uint(*keys).astype(F32) * F32(1.0 / 0xFFFFFFFF)


# ---------------------------------------------------------------------------------------
# Perlin noise

def _fade(t):
    return t * t * t * (t * (t * F32(6.0) - F32(15.0)) + F32(10.0))


def _negate_if(value, bit, h):
    """``-value`` where bit ``bit`` of ``h`` is set: flips the float's sign bit, as the
    SSE kernels of Cycles do."""
    value = np.ascontiguousarray(value, dtype=F32)
    sign = ((h >> np.uint32(bit)) & np.uint32(1)) << np.uint32(31)
    return (value.view(np.uint32) ^ sign).view(F32)


def _floorfrac(x):
    i = np.floor(x)
    return (x - i).astype(F32), i.astype(np.int32)


def _grad1(h, x):
    h = h & np.uint32(15)
    g = F32(1.0) + (h & np.uint32(7)).astype(F32)
    return _negate_if(g, 3, h) * x


def _grad2(h, x, y):
    h = h & np.uint32(7)
    u = np.where(h < 4, x, y)
    v = F32(2.0) * np.where(h < 4, y, x)
    return _negate_if(u, 0, h) + _negate_if(v, 1, h)


def _grad3(h, x, y, z):
    # In place where it can (``h`` and the chosen coordinates are fresh arrays): the same
    # choices and sign flips as _negate_if, without its temporaries.
    h = np.bitwise_and(h, np.uint32(15), out=h)
    u = np.where(h < 8, x, y)
    twelve_or_fourteen = h == 12
    twelve_or_fourteen |= h == 14
    v = np.where(h < 4, y, np.where(twelve_or_fourteen, x, z))
    sign = np.bitwise_and(h, np.uint32(1))
    sign <<= np.uint32(31)
    u.view(np.uint32)[...] ^= sign
    np.bitwise_and(h, np.uint32(2), out=sign)
    sign <<= np.uint32(30)
    v.view(np.uint32)[...] ^= sign
    u += v
    return u


def _grad4(h, x, y, z, w):
    h = h & np.uint32(31)
    u = np.where(h < 24, x, y)
    v = np.where(h < 16, y, z)
    s = np.where(h < 8, z, w)
    return _negate_if(u, 0, h) + _negate_if(v, 1, h) + _negate_if(s, 2, h)


def _lerp(a, b, t):
    return (F32(1.0) - t) * a + t * b


def perlin(p: np.ndarray) -> np.ndarray:
    """Raw (unscaled) Perlin noise of ``p`` with shape (..., D), D in 1..4."""
    p = np.asarray(p, dtype=F32)
    dims = p.shape[-1]
    fracs, cells = zip(*(_floorfrac(p[..., k]) for k in range(dims)))
    fades = [_fade(f) for f in fracs]
    grad = {1: _grad1, 2: _grad2, 3: _grad3, 4: _grad4}[dims]
    hasher = _CornerHash(cells)
    with np.errstate(over="ignore"):
        def corner(offsets):
            h = hasher(offsets)
            return grad(h, *(fracs[k] - F32(offsets[k]) for k in range(dims)))

        def blend(chosen):
            # Choose corners from the last axis down and interpolate x innermost, the
            # order of operations of Cycles' bi_mix / tri_mix / quad_mix.
            if len(chosen) == dims:
                return corner(tuple(reversed(chosen)))
            axis = dims - 1 - len(chosen)
            return _lerp(blend(chosen + (0,)), blend(chosen + (1,)), fades[axis])

        return blend(())


class _CornerHash:
    """``hash_uint`` of a Perlin cell's corners (the cell's integer coordinates plus 0 or 1
    per axis), computed in place in buffers kept across the corners.

    ``hash_uint``'s arithmetic (``_mix``, ``_final``), without a new array per corner:
    a frame's noise is millions of points, where fresh arrays of that size each cost page
    faults on top of the integer operations (3-D fbm of 180k points took 1.55x as long with
    them, and the 3-D gradients' temporaries, now gone too, a share of that; medians of 7).
    """

    def __init__(self, cells):
        n = len(cells)
        init = _hash_init(n)
        shape = np.broadcast_shapes(*(np.shape(c) for c in cells))
        with np.errstate(over="ignore"):
            # Each key with the hash's initial value added (a, b, c start from it).
            self.bases = [np.broadcast_to(np.asarray(c).view(np.uint32) + init, shape) for c in cells]
        self.n = n
        self.abc = [np.empty(shape, np.uint32) for _ in range(3)]
        self.scratch = (np.empty(shape, np.uint32), np.empty(shape, np.uint32))
        self.init = init

    def __call__(self, offsets) -> np.ndarray:
        """The hash of the corner at ``offsets`` (one 0/1 per axis); a new array."""
        a, b, c = self.abc
        bases, n = self.bases, self.n
        with np.errstate(over="ignore"):
            starts = [np.add(bases[k], np.uint32(offsets[k])) if offsets[k] else bases[k]
                      for k in range(n)]
            for target, k in ((a, 0), (b, 1), (c, 2)):
                if k < n:
                    np.copyto(target, starts[k])
                else:
                    target.fill(self.init)
            if n == 4:
                _mix(a, b, c, self.scratch)
                np.add(a, starts[3], out=a)
                # keys[3] went in after the mix; the initial value it carries in ``bases``
                # must not: hash_uint4 adds the bare key.
                np.subtract(a, self.init, out=a)
            _final(a, b, c, self.scratch)
            return c.copy()


def snoise(p: np.ndarray) -> np.ndarray:
    """Signed noise in about [-1, 1], repeated every 100000 units like Cycles."""
    p = np.fmod(np.asarray(p, dtype=F32), F32(100000.0))
    return _NOISE_SCALE[p.shape[-1]] * perlin(p)


# ---------------------------------------------------------------------------------------
# Fractal variants (Detail = octaves - 1, fractional part blends in one more octave)

def _octave_count(detail):
    return np.trunc(detail).astype(np.int32)


def fbm(p, detail, roughness, lacunarity, normalize):
    p = np.asarray(p, dtype=F32)
    shape = p.shape[:-1]
    detail = np.broadcast_to(np.asarray(detail, dtype=F32), shape)
    roughness = np.broadcast_to(np.asarray(roughness, dtype=F32), shape)
    lacunarity = np.broadcast_to(np.asarray(lacunarity, dtype=F32), shape)
    octaves = _octave_count(detail)
    fscale = np.ones(shape, F32)
    amp = np.ones(shape, F32)
    maxamp = np.zeros(shape, F32)
    total = np.zeros(shape, F32)
    for i in range(int(octaves.max(initial=0)) + 1):
        active = i <= octaves
        t = snoise(fscale[..., None] * p)
        total = np.where(active, total + t * amp, total)
        maxamp = np.where(active, maxamp + amp, maxamp)
        amp = np.where(active, amp * roughness, amp)
        fscale = np.where(active, fscale * lacunarity, fscale)
    rmd = detail - np.floor(detail)
    if not np.any(rmd != 0):
        return F32(0.5) * total / maxamp + F32(0.5) if normalize else total
    t = snoise(fscale[..., None] * p)
    total2 = total + t * amp
    if normalize:
        whole = F32(0.5) * total / maxamp + F32(0.5)
        blended = _lerp(whole, F32(0.5) * total2 / (maxamp + amp) + F32(0.5), rmd)
    else:
        whole = total
        blended = _lerp(total, total2, rmd)
    return np.where(rmd != 0, blended, whole)


def multi_fractal(p, detail, roughness, lacunarity):
    p = np.array(p, dtype=F32)
    shape = p.shape[:-1]
    detail = np.broadcast_to(np.asarray(detail, dtype=F32), shape)
    roughness = np.broadcast_to(np.asarray(roughness, dtype=F32), shape)
    lacunarity = np.broadcast_to(np.asarray(lacunarity, dtype=F32), shape)
    octaves = _octave_count(detail)
    value = np.ones(shape, F32)
    pwr = np.ones(shape, F32)
    for i in range(int(octaves.max(initial=0)) + 1):
        active = i <= octaves
        value = np.where(active, value * (pwr * snoise(p) + F32(1.0)), value)
        pwr = np.where(active, pwr * roughness, pwr)
        p = np.where(active[..., None], p * lacunarity[..., None], p)
    rmd = detail - np.floor(detail)
    return np.where(rmd != 0, value * (rmd * pwr * snoise(p) + F32(1.0)), value)


def hetero_terrain(p, detail, roughness, lacunarity, offset):
    p = np.array(p, dtype=F32)
    shape = p.shape[:-1]
    detail = np.broadcast_to(np.asarray(detail, dtype=F32), shape)
    roughness = np.broadcast_to(np.asarray(roughness, dtype=F32), shape)
    lacunarity = np.broadcast_to(np.asarray(lacunarity, dtype=F32), shape)
    offset = np.broadcast_to(np.asarray(offset, dtype=F32), shape)
    octaves = _octave_count(detail)
    pwr = roughness.copy()
    value = offset + snoise(p)
    p = p * lacunarity[..., None]
    for i in range(1, int(octaves.max(initial=0)) + 1):
        active = i <= octaves
        increment = (snoise(p) + offset) * pwr * value
        value = np.where(active, value + increment, value)
        pwr = np.where(active, pwr * roughness, pwr)
        p = np.where(active[..., None], p * lacunarity[..., None], p)
    rmd = detail - np.floor(detail)
    increment = (snoise(p) + offset) * pwr * value
    return np.where(rmd != 0, value + rmd * increment, value)


def hybrid_multi_fractal(p, detail, roughness, lacunarity, offset, gain):
    p = np.array(p, dtype=F32)
    shape = p.shape[:-1]
    detail = np.broadcast_to(np.asarray(detail, dtype=F32), shape)
    roughness = np.broadcast_to(np.asarray(roughness, dtype=F32), shape)
    lacunarity = np.broadcast_to(np.asarray(lacunarity, dtype=F32), shape)
    offset = np.broadcast_to(np.asarray(offset, dtype=F32), shape)
    gain = np.broadcast_to(np.asarray(gain, dtype=F32), shape)
    octaves = _octave_count(detail)
    pwr = np.ones(shape, F32)
    value = np.zeros(shape, F32)
    weight = np.ones(shape, F32)
    for i in range(int(octaves.max(initial=0)) + 1):
        active = (weight > F32(0.001)) & (i <= octaves)
        weight = np.where(active, np.minimum(weight, F32(1.0)), weight)
        signal = (snoise(p) + offset) * pwr
        pwr = np.where(active, pwr * roughness, pwr)
        value = np.where(active, value + weight * signal, value)
        weight = np.where(active, weight * gain * signal, weight)
        p = np.where(active[..., None], p * lacunarity[..., None], p)
    rmd = detail - np.floor(detail)
    last = (rmd != 0) & (weight > F32(0.001))
    weight = np.minimum(weight, F32(1.0))
    signal = (snoise(p) + offset) * pwr
    return np.where(last, value + rmd * weight * signal, value)


def ridged_multi_fractal(p, detail, roughness, lacunarity, offset, gain):
    p = np.array(p, dtype=F32)
    shape = p.shape[:-1]
    detail = np.broadcast_to(np.asarray(detail, dtype=F32), shape)
    roughness = np.broadcast_to(np.asarray(roughness, dtype=F32), shape)
    lacunarity = np.broadcast_to(np.asarray(lacunarity, dtype=F32), shape)
    offset = np.broadcast_to(np.asarray(offset, dtype=F32), shape)
    gain = np.broadcast_to(np.asarray(gain, dtype=F32), shape)
    octaves = _octave_count(detail)
    pwr = roughness.copy()
    signal = offset - np.abs(snoise(p))
    signal = signal * signal
    value = signal.copy()
    for i in range(1, int(octaves.max(initial=0)) + 1):
        active = i <= octaves
        p = np.where(active[..., None], p * lacunarity[..., None], p)
        weight = np.clip(signal * gain, F32(0.0), F32(1.0))
        new_signal = offset - np.abs(snoise(p))
        new_signal = new_signal * new_signal * weight
        signal = np.where(active, new_signal, signal)
        value = np.where(active, value + new_signal * pwr, value)
        pwr = np.where(active, pwr * roughness, pwr)
    return value


def fractal(p, noise_type, detail, roughness, lacunarity, offset, gain, normalize):
    """Cycles' ``noise_select``: the fractal sum the Noise Texture's type asks for."""
    if noise_type == "FBM":
        return fbm(p, detail, roughness, lacunarity, normalize)
    if noise_type == "MULTIFRACTAL":
        return multi_fractal(p, detail, roughness, lacunarity)
    if noise_type == "HYBRID_MULTIFRACTAL":
        return hybrid_multi_fractal(p, detail, roughness, lacunarity, offset, gain)
    if noise_type == "RIDGED_MULTIFRACTAL":
        return ridged_multi_fractal(p, detail, roughness, lacunarity, offset, gain)
    if noise_type == "HETERO_TERRAIN":
        return hetero_terrain(p, detail, roughness, lacunarity, offset)
    raise ValueError(f"unknown noise type {noise_type}")


def _random_offset(seed: float, dims: int) -> np.ndarray:
    """The per-seed coordinate offsets in [100, 200] Cycles adds for distortion and colour."""
    if dims == 1:
        return F32(100.0) + hash_float_to_float(F32(seed))[None] * F32(100.0)
    return np.array([F32(100.0) + hash_float_to_float(F32(seed), F32(k)) * F32(100.0)
                     for k in range(dims)], dtype=F32)


def noise_texture(vector, w, *, dimensions: int = 3, noise_type: str = "FBM",
                  normalize: bool = True, scale=5.0, detail=2.0, roughness=0.5,
                  lacunarity=2.0, offset=0.0, gain=1.0, distortion=0.0,
                  want_color: bool = False):
    """The Noise Texture node of Cycles (``svm_node_tex_noise``).

    Parameters
    ----------
    vector : (N, 3) array
        The Vector input (texture coordinates); unused for 1-D noise.
    w : scalar or (N,) array
        The W input; used by 1-D and 4-D noise.
    dimensions, noise_type, normalize
        The node's properties (``noise_dimensions`` as an int, ``noise_type``, ``normalize``).
    scale, detail, roughness, lacunarity, offset, gain, distortion
        Socket values, scalars or (N,) arrays.
    want_color : bool
        Also compute the Color output (two more fractal evaluations).

    Returns
    -------
    (fac, color)
        ``fac`` (N,) float32; ``color`` (N, 3) float32 or None.
    """
    vector = np.asarray(vector, dtype=F32)
    n = vector.shape[0]
    scale = np.asarray(scale, dtype=F32)
    detail = np.clip(np.asarray(detail, dtype=F32), F32(0.0), F32(15.0))
    roughness = np.maximum(np.asarray(roughness, dtype=F32), F32(0.0))
    distortion = np.broadcast_to(np.asarray(distortion, dtype=F32), (n,))
    w = np.broadcast_to(np.asarray(w, dtype=F32), (n,)) * scale
    vector = vector * scale[..., None] if scale.ndim else vector * scale
    if dimensions == 1:
        p = w[:, None]
    elif dimensions == 2:
        p = vector[:, :2]
    elif dimensions == 3:
        p = vector[:, :3]
    elif dimensions == 4:
        p = np.concatenate([vector[:, :3], w[:, None]], axis=1)
    else:
        raise ValueError(f"noise dimensions must be 1 to 4, got {dimensions}")
    p = np.ascontiguousarray(p, dtype=F32)
    if np.any(distortion != 0):
        shifts = np.stack([snoise(p + _random_offset(float(k), dimensions))
                           for k in range(dimensions)], axis=-1)
        p = np.where((distortion != 0)[:, None], p + shifts * distortion[:, None], p)
    args = (noise_type, detail, roughness, lacunarity, offset, gain, normalize)
    fac = fractal(p, *args)
    color = None
    if want_color:
        seeds = {1: (1.0, 2.0), 2: (2.0, 3.0), 3: (3.0, 4.0), 4: (4.0, 5.0)}[dimensions]
        color = np.stack([fac] + [fractal(p + _random_offset(s, dimensions), *args)
                                  for s in seeds], axis=-1)
    return fac.astype(F32), color
