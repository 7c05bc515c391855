"""The OpenVDB grids of a volume object as Cycles samples them, and where Cycles renders it.

A grid's voxels (read through geometry nodes by ``addon.scene.volume_grids``) are sampled as
Cycles' volume lookup does on NanoVDB: object to index space, trilinear (tricubic with Cubic
interpolation), the background value outside. Cycles renders a volume object as the union of
the 8^3-voxel leaf boxes holding active voxels (above the clipping, dilated by the
interpolation's padding); outside them the shader is not evaluated, so the extinction is 0
whatever the material does."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

#: OpenVDB leaf nodes are 8^3 voxels; Cycles' volume mesh is made of whole leaves.
LEAF = 8


def _affine(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    m = np.asarray(matrix, dtype=np.float64)
    return points @ m[:3, :3].T + m[:3, 3]


def _cubic_weights(t: np.ndarray) -> list[np.ndarray]:
    """Uniform cubic B-spline weights of Cycles' ``fill_cubic_weights``."""
    return [(((-1.0 / 6.0) * t + 0.5) * t - 0.5) * t + 1.0 / 6.0,
            ((0.5 * t - 1.0) * t) * t + 2.0 / 3.0,
            ((-0.5 * t + 0.5) * t + 0.5) * t + 1.0 / 6.0,
            (1.0 / 6.0) * t * t * t]


@dataclass
class VoxelGrid:
    """One grid of a volume object: voxels of a dense index box and how to sample them.

    ``values`` holds the voxels with index (i, j, k) = ``origin`` + array position, shape
    (nx, ny, nz) for a float grid or (nx, ny, nz, 3) for a vector grid; ``index_to_object``
    is the grid's transform (voxel centres at integer index coordinates).
    """

    name: str
    values: np.ndarray
    origin: np.ndarray                 # (3,) int
    index_to_object: np.ndarray        # (4, 4)
    interpolation: str = "LINEAR"      # the material's volume interpolation: LINEAR or CUBIC
    background: float = 0.0

    def __post_init__(self):
        self.object_to_index = np.linalg.inv(np.asarray(self.index_to_object, dtype=np.float64))
        # A border of background voxels as wide as the filter reaches, so every tap of a
        # point inside the padded block is a plain lookup in one flat array.
        self._pad = 2 if self.interpolation == "CUBIC" else 1
        pad = [(self._pad, self._pad)] * 3 + [(0, 0)] * (self.values.ndim - 3)
        padded = np.pad(np.asarray(self.values, dtype=np.float32), pad,
                        constant_values=self.background)
        self._shape = np.array(padded.shape[:3])
        self._flat = padded.reshape(int(np.prod(self._shape)), -1)

    @property
    def channels(self) -> int:
        return 1 if self.values.ndim == 3 else self.values.shape[3]

    def index_coordinates(self, object_points: np.ndarray) -> np.ndarray:
        return _affine(self.object_to_index, object_points) - self.origin

    def sample(self, object_points: np.ndarray) -> np.ndarray:
        """Values at object-space points: (N,) for a float grid, (N, 3) for a vector grid."""
        p = self.index_coordinates(np.asarray(object_points, dtype=np.float64)) + self._pad
        base = np.floor(p)
        t = p - base
        base = base.astype(np.int64)
        cubic = self.interpolation == "CUBIC"
        taps = (-1, 0, 1, 2) if cubic else (0, 1)
        # Points whose taps would leave the padded block see only background there.
        inside = np.all((base + taps[0] >= 0) & (base + taps[-1] < self._shape), axis=1)
        base = np.where(inside[:, None], base, self._pad)
        ny, nz = int(self._shape[1]), int(self._shape[2])
        flat = (base[:, 0] * ny + base[:, 1]) * nz + base[:, 2]
        if cubic:
            weights = [_cubic_weights(t[:, axis]) for axis in range(3)]
        else:
            weights = [[1.0 - t[:, axis], t[:, axis]] for axis in range(3)]
        out = np.zeros((len(p), self._flat.shape[1]), dtype=np.float64)
        for a, wx in zip(taps, weights[0]):
            for b, wy in zip(taps, weights[1]):
                wxy = wx * wy
                for c, wz in zip(taps, weights[2]):
                    out += self._flat[flat + ((a * ny + b) * nz + c)] * (wxy * wz)[:, None]
        out = np.where(inside[:, None], out, self.background)
        return out[:, 0] if self.values.ndim == 3 else out


@dataclass
class VoxelRegion:
    """Where Cycles renders a volume object: a set of whole leaves of its first grid's
    index space (see the module notes), plus the box around them for ray intervals."""

    leaves: np.ndarray                 # (lx, ly, lz) bool
    leaf_origin: np.ndarray            # (3,) int: leaf index of leaves[0, 0, 0]
    index_to_object: np.ndarray        # (4, 4)
    object_to_world: np.ndarray        # (4, 4)
    #: (lo, hi) index-space box of the active voxels widened by the interpolation's
    #: reach: the only place the density is not zero (None: the leaves' box).
    core: tuple | None = None

    def __post_init__(self):
        index_to_world = np.asarray(self.object_to_world, np.float64) @ np.asarray(
            self.index_to_object, np.float64)
        self.world_to_index = np.linalg.inv(index_to_world)

    @staticmethod
    def from_grids(grids: list[VoxelGrid], clipping: float, padding: int,
                   object_to_world: np.ndarray) -> "VoxelRegion":
        """The region of the active voxels (value >= ``clipping`` in any channel) of
        ``grids`` (which must share the first one's transform), dilated by ``padding``."""
        first = grids[0]
        lo = np.min([g.origin for g in grids], axis=0) - padding
        hi = np.max([g.origin + np.array(g.values.shape[:3]) for g in grids], axis=0) + padding
        active = np.zeros(tuple(hi - lo), dtype=bool)
        for grid in grids:
            values = grid.values if grid.values.ndim == 3 else grid.values.max(axis=3)
            start = grid.origin - lo
            end = start + np.array(values.shape)
            active[start[0]:end[0], start[1]:end[1], start[2]:end[2]] |= values >= clipping
        if padding > 0:
            active = ndimage.binary_dilation(active, ndimage.generate_binary_structure(3, 1),
                                             iterations=padding)
        leaf_lo = np.floor_divide(lo, LEAF)
        leaf_hi = np.floor_divide(hi - 1, LEAF) + 1
        padded = np.zeros(tuple((leaf_hi - leaf_lo) * LEAF), dtype=bool)
        start = lo - leaf_lo * LEAF
        padded[start[0]:start[0] + active.shape[0], start[1]:start[1] + active.shape[1],
               start[2]:start[2] + active.shape[2]] = active
        leaves = padded.reshape(padded.shape[0] // LEAF, LEAF, padded.shape[1] // LEAF, LEAF,
                                padded.shape[2] // LEAF, LEAF).any(axis=(1, 3, 5))
        core = None
        if active.any():
            # Dilated by ``padding`` already: one voxel (linear) or two (cubic) around
            # the active ones, as far as their interpolation reaches.
            used = np.argwhere(active)
            core = (used.min(axis=0) + lo - 1e-3, used.max(axis=0) + lo + 1e-3)
        return VoxelRegion(leaves=leaves, leaf_origin=leaf_lo, index_to_object=first.index_to_object,
                           object_to_world=object_to_world, core=core)

    @property
    def empty(self) -> bool:
        return not self.leaves.any()

    def _leaf_box(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) in index space of the box around the active leaves."""
        used = np.argwhere(self.leaves)
        return ((used.min(axis=0) + self.leaf_origin) * LEAF,
                (used.max(axis=0) + 1 + self.leaf_origin) * LEAF)

    def world_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World-space (lo, hi) box around the active leaves (the object's bounds, as
        Cycles' camera-in-volume test sees them)."""
        lo, hi = self._leaf_box()
        corners = np.array([[(lo, hi)[(k >> axis) & 1][axis] for axis in range(3)]
                            for k in range(8)], dtype=np.float64)
        world = _affine(np.linalg.inv(self.world_to_index), corners)
        return world.min(axis=0), world.max(axis=0)

    def contains(self, points: np.ndarray) -> np.ndarray:
        """True where world-space points lie inside an active leaf box."""
        q = _affine(self.world_to_index, np.asarray(points, dtype=np.float64))
        leaf = np.floor(q / LEAF).astype(np.int64) - self.leaf_origin
        shape = np.array(self.leaves.shape)
        inside = np.all((leaf >= 0) & (leaf < shape), axis=1)
        leaf = np.clip(leaf, 0, shape - 1)
        return inside & self.leaves[leaf[:, 0], leaf[:, 1], leaf[:, 2]]

    def intervals(self, origins: np.ndarray, directions: np.ndarray, t_near: np.ndarray,
                  t_far: np.ndarray, core: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(ray index, t0, t1) where rays cross the box around the active leaves (with
        ``core``, the tighter box of the active voxels), clipped to [t_near, t_far].
        Distances stay those of the world rays (the map to index space is affine, so the
        ray parameter carries over)."""
        if self.empty:
            return np.zeros(0, np.int64), np.zeros(0), np.zeros(0)
        lo, hi = self.core if core and self.core is not None else self._leaf_box()
        m = self.world_to_index
        o = _affine(m, origins)
        d = directions @ m[:3, :3].T
        with np.errstate(divide="ignore", invalid="ignore"):
            a = (lo - o) / d
            b = (hi - o) / d
        parallel = d == 0.0
        outside = parallel & ((o < lo) | (o > hi))
        near = np.where(parallel, -np.inf, np.minimum(a, b)).max(axis=1)
        far = np.where(parallel, np.inf, np.maximum(a, b)).min(axis=1)
        t0 = np.maximum(near, t_near)
        t1 = np.minimum(far, t_far)
        keep = np.flatnonzero(~outside.any(axis=1) & (t1 > t0))
        return keep, t0[keep], t1[keep]
