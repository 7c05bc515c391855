"""A participating medium as the X map needs it: where it is and its extinction field.

``addon.scene.geometry`` builds these from the scene; ``core.maps.transmittance`` integrates
them along camera rays. A medium is either evaluable here (a constant extinction, or a
shader graph numpy can evaluate) or it names why not, and then Cycles itself measures its
transmittance (``addon.maps.transmittance_oracle``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from .shader_graph import GraphEvaluator, ShaderGraph, evaluate_extinction
from .shader_link import Link
from .shader_nodes import NodeContext


@dataclass
class VolumeMedium:
    """One medium: the world volume, or one object instance with a volume material.

    ``key`` identifies the instance across runs (the ray cache stores its intervals under
    it); ``kind`` is "world", "mesh" or "volume_object". ``world_to_object`` and
    ``texspace`` place the object's coordinate systems for texture lookups. A volume
    object carries the grids its material reads (``grids``) and the region where Cycles
    renders it (``region``, a ``core.media.voxel_grid.VoxelRegion``): its extinction is 0
    outside that region, and its ray intervals are found there, not in the ray cache.
    ``density_scale`` multiplies its extinction: a volume object whose density is given
    in object space (Blender's default) has Cycles divide the density by the object's
    scale, so that scaling a smoke down does not thin it out (``volume_density_scale``).
    """

    key: str
    name: str
    kind: str
    material: str | None
    graph: ShaderGraph
    world_to_object: np.ndarray | None = None
    texspace: tuple[tuple, tuple] | None = None
    unsupported: str | None = None          # set when only Cycles can evaluate it
    grids: dict | None = None
    region: object | None = None
    extra: dict = field(default_factory=dict)
    density_scale: float = 1.0

    @property
    def evaluable(self) -> bool:
        return self.unsupported is None and self.graph.unsupported is None

    @property
    def reason(self) -> str | None:
        return self.unsupported or self.graph.unsupported

    def context(self, points: np.ndarray) -> NodeContext:
        return NodeContext(points=np.asarray(points, dtype=np.float64),
                           world_to_object=self.world_to_object, texspace=self.texspace,
                           grids=self.grids)

    def constant_extinction(self) -> np.ndarray | None:
        """The extinction (3,) when it is the same everywhere, else None (always for a
        volume object: it ends where its voxels do)."""
        if not self.evaluable or self.kind == "volume_object" or self.graph.depends_on_position():
            return None
        return evaluate_extinction(self.graph, self.context(np.zeros((1, 3))))[0].astype(np.float64)

    def extinction(self, points: np.ndarray, part: str = "extinction") -> np.ndarray:
        """Extinction (N, 3) at world-space points (``part`` "scattering": its scattering
        part, what in-scatters the lights' light)."""
        extinction = evaluate_extinction(self.graph, self.context(points), part)
        if self.density_scale != 1.0:
            extinction = extinction * self.density_scale
        if self.region is not None:
            extinction = extinction * self.region.contains(points)[:, None]
        return extinction

    def coefficients(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(extinction, scattering, emission), each (N, 3), at world-space points: one walk of
        the shader graph for all three (its textures evaluated once)."""
        evaluator = GraphEvaluator(self.graph, self.context(points))
        scale = self.density_scale
        if self.region is not None:
            scale = scale * self.region.contains(points)[:, None]
        return tuple(np.nan_to_num(evaluator.extinction(part), nan=0.0, posinf=1e30, neginf=0.0) * scale
                     for part in ("extinction", "scattering", "emission"))

    def describe(self) -> dict:
        constant = self.constant_extinction() if self.evaluable else None
        return {"key": self.key, "name": self.name, "kind": self.kind, "material": self.material,
                "evaluated_by": "numpy" if self.evaluable else "cycles",
                "reason": self.reason,
                "homogeneous": constant is not None,
                "extinction": None if constant is None else [float(v) for v in constant]}


def volume_density_scale(object_to_world: np.ndarray, object_space: bool) -> float:
    """What Cycles multiplies a volume object's density by (``object_volume_density`` in
    its scene/object.cpp). With the density in object space: one over the length of the
    object's unit diagonal mapped to world space, so a smoke scaled down by s becomes 1/s
    times denser and keeps its optical depth across it. In world space: 1."""
    if not object_space:
        return 1.0
    diagonal = np.asarray(object_to_world, dtype=np.float64)[:3, :3] @ np.full(3, 1.0 / math.sqrt(3.0))
    length = float(np.linalg.norm(diagonal))
    return 1.0 / length if length > 0.0 else 1.0


def check_densities(medium: VolumeMedium) -> None:
    """Refuse negative or NaN densities that are the same everywhere (typed into a socket
    or computed from constants). A density driven by a texture that dips below zero is
    clamped at zero, as Cycles clamps it."""
    if medium.graph.unsupported is not None:
        return
    constant = not medium.graph.depends_on_position()
    evaluator = GraphEvaluator(medium.graph, medium.context(np.zeros((1, 3))))
    for node in medium.graph.nodes.values():
        if node.type not in ("PRINCIPLED_VOLUME", "VOLUME_SCATTER", "VOLUME_ABSORPTION"):
            continue
        if isinstance(node.inputs.get("Density"), Link) and not constant:
            continue
        value = float(np.ravel(evaluator.input(node, "Density", 1.0))[0])
        if math.isnan(value) or value < 0.0:
            where = medium.name if medium.material is None else f"{medium.name}' material '{medium.material}"
            raise InputError(f"medium '{where}': volume node '{node.name}' has density {value:g}; "
                             "densities must be finite and >= 0")
