"""A volume shader as plain data, and its extinction evaluated at points in numpy.

``addon.scene.shader_export`` turns the node tree feeding a material's (or the world's) Volume
output into a :class:`ShaderGraph`: node groups flattened, reroutes and muted nodes
resolved, colour ramps baked into the 256-entry table Cycles itself uses. This module
evaluates that graph the way Cycles' SVM does: socket type conversions, Add/Mix Shader
weights and the extinction of each volume closure, giving the extinction coefficient per
RGB channel at any set of world-space points.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .shader_link import Link
from .shader_nodes import NODE_FUNCTIONS, POSITION_NODES, NodeContext

#: Rec. 709 luminance: what Cycles' colour-to-float conversion uses in the default
#: scene-linear space (``linear_rgb_to_gray``).
_GRAY = np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)
#: Cycles drops closures whose weight is below this (``CLOSURE_WEIGHT_CUTOFF``).
CLOSURE_WEIGHT_CUTOFF = 1e-5
#: Shader-combining nodes and volume closures the graph walk understands.
SHADER_NODES = ("ADD_SHADER", "MIX_SHADER")
VOLUME_CLOSURES = ("PRINCIPLED_VOLUME", "VOLUME_SCATTER", "VOLUME_ABSORPTION",
                   "VOLUME_COEFFICIENTS")
#: Closures that may feed a Volume output without adding extinction (they emit light).
NON_EXTINCTION_CLOSURES = ("EMISSION", "HOLDOUT", "BACKGROUND")


@dataclass
class Node:
    """One shader node: its Blender type, the properties that matter, its inputs.

    ``inputs`` maps socket identifiers to a :class:`Link` or a constant (float, or a tuple
    of 3 for vectors and colours); ``input_kinds`` gives each input's socket type.
    """

    type: str
    name: str
    props: dict = field(default_factory=dict)
    inputs: dict = field(default_factory=dict)
    input_kinds: dict = field(default_factory=dict)


@dataclass
class ShaderGraph:
    """The nodes feeding a Volume output; ``root`` is the link into that output."""

    nodes: dict[str, Node]
    root: Link | None
    unsupported: str | None = None    # why numpy cannot evaluate it (then Cycles must)

    @property
    def empty(self) -> bool:
        return self.root is None

    def depends_on_position(self) -> bool:
        """True when some reachable node reads coordinates (textures, positions)."""
        return any(node.type in POSITION_NODES or uses_default_coordinates(node)
                   for node in self.nodes.values())


def uses_default_coordinates(node: Node) -> bool:
    # Texture nodes with an unlinked Vector input read the Generated coordinates.
    return node.type.startswith("TEX_") and not isinstance(node.inputs.get("Vector"), Link)


# ---------------------------------------------------------------------------------------
# Evaluation

def convert(value, source: str, target: str):
    """Cycles' implicit socket conversions (``ConvertNode``) between value kinds."""
    if source == target or target == "SHADER":
        return value
    value = np.asarray(value, dtype=np.float32)
    if target == "VALUE":
        if source == "RGBA":
            return value @ _GRAY
        if source == "VECTOR":
            return value.sum(axis=-1) * np.float32(1.0 / 3.0)
        return value
    # VALUE -> VECTOR / RGBA repeats the value; VECTOR <-> RGBA is the identity.
    if source == "VALUE":
        return np.repeat(value[..., None], 3, axis=-1)
    return value


class GraphEvaluator:
    """Evaluates a ShaderGraph at ``NodeContext.points``; each node output computed once."""

    def __init__(self, graph: ShaderGraph, context: NodeContext):
        self.graph = graph
        self.context = context
        self._outputs: dict[str, dict[str, np.ndarray]] = {}

    def input(self, node: Node, identifier: str, default=0.0):
        """The value arriving at an input socket, in that socket's own kind."""
        value = node.inputs.get(identifier, default)
        kind = node.input_kinds.get(identifier, "VALUE")
        if isinstance(value, Link):
            return convert(self.output(value), value.kind, kind)
        array = np.asarray(value, dtype=np.float32)
        if kind in ("VECTOR", "RGBA") and array.ndim == 0:
            array = np.repeat(array, 3)
        elif kind == "VALUE" and array.ndim == 1:
            array = convert(array, "RGBA" if len(array) >= 3 else "VALUE", "VALUE")
        return array

    def output(self, link: Link) -> np.ndarray:
        if link.node not in self._outputs:
            node = self.graph.nodes[link.node]
            function = NODE_FUNCTIONS.get(node.type)
            if function is None:
                raise ValueError(f"node {node.name} ({node.type}) cannot be evaluated")
            self._outputs[link.node] = function(self, node)
        outputs = self._outputs[link.node]
        if link.socket not in outputs:
            raise ValueError(f"output {link.socket} of node {link.node} is not supported")
        return outputs[link.socket]

    # --- closures -------------------------------------------------------------------
    def extinction(self, part: str = "extinction") -> np.ndarray:
        """Extinction coefficient (N, 3) at the context's points; with ``part`` "scattering",
        only its scattering part (what in-scatters light; absorption left out); with
        "emission", the light the medium emits per unit length instead."""
        n = len(self.context.points)
        if self.graph.root is None:
            return np.zeros((n, 3), np.float32)
        total = self._closure(self.graph.root, np.ones(n, np.float32), part)
        return np.broadcast_to(total, (n, 3)).astype(np.float32)

    def _closure(self, link: Link, weight: np.ndarray, part: str):
        node = self.graph.nodes[link.node]
        if node.type == "ADD_SHADER":
            out = 0.0
            for key in ("Shader", "Shader_001"):
                child = node.inputs.get(key)
                if isinstance(child, Link):
                    out = out + self._closure(child, weight, part)
            return out
        if node.type == "MIX_SHADER":
            fac = np.clip(self.input(node, "Fac"), 0.0, 1.0)
            out = 0.0
            for key, w in (("Shader", 1.0 - fac), ("Shader_001", fac)):
                child = node.inputs.get(key)
                if isinstance(child, Link):
                    out = out + self._closure(child, weight * w, part)
            return out
        if part == "emission":
            return closure_emission_field(self, node, weight)
        if node.type in NON_EXTINCTION_CLOSURES:
            return 0.0
        if node.type not in VOLUME_CLOSURES:
            raise ValueError(f"{node.name} ({node.type}) is not a volume shader")
        return closure_extinction_field(self, node, weight, part)


def closure_extinction_field(ev: GraphEvaluator, node: Node, weight, part: str = "extinction") -> np.ndarray:
    """Extinction of one volume closure node, as Cycles' SVM computes it (``part``
    "scattering": its scattering coefficient alone).

    Density is clamped at zero (``fmaxf(density, 0)``); colours are not clamped except
    where Cycles clamps them. Principled Volume takes the square root of the absorption
    colour before using it.
    """
    weight = np.asarray(weight, dtype=np.float32)
    if node.type == "VOLUME_COEFFICIENTS":
        absorption = ev.input(node, "Absorption Coefficients")
        scatter = ev.input(node, "Scatter Coefficients")
        return weight[..., None] * (scatter if part == "scattering" else absorption + scatter)
    density = weight * np.maximum(np.nan_to_num(ev.input(node, "Density", 1.0)), 0.0)
    color = ev.input(node, "Color", (1.0, 1.0, 1.0))
    if node.type == "PRINCIPLED_VOLUME":
        # On a volume object the grids named by the attribute sockets scale density and
        # colour (``svm_node_principled_volume``); elsewhere nothing has those names.
        grid = ev.context.grid(node.inputs.get("Density Attribute"))
        if grid is not None:
            density = np.maximum(density * (grid if grid.ndim == 1 else grid.mean(axis=1)), 0.0)
        tint = ev.context.grid(node.inputs.get("Color Attribute"))
        if tint is not None:
            color = color * (tint[:, None] if tint.ndim == 1 else tint)
    if node.type == "VOLUME_SCATTER":
        return density[..., None] * color
    if node.type == "VOLUME_ABSORPTION":
        return density[..., None] * (0.0 if part == "scattering" else 1.0 - color)
    # PRINCIPLED_VOLUME
    absorption_color = np.sqrt(np.maximum(ev.input(node, "Absorption Color"), 0.0))
    absorption = np.maximum(1.0 - color, 0.0) * np.maximum(1.0 - absorption_color, 0.0)
    extinction = density[..., None] * (color if part == "scattering" else color + absorption)
    return np.where((density > CLOSURE_WEIGHT_CUTOFF)[..., None], extinction, 0.0)


#: Cycles' blackbody radiance per T^4 (Stefan-Boltzmann over pi, in its units).
_BLACKBODY_SIGMA = 5.670373e-8 * 1e-6 / np.pi


def closure_emission_field(ev: GraphEvaluator, node: Node, weight) -> np.ndarray:
    """The emission (N, 3) one closure node adds inside a volume, as Cycles' SVM computes it:
    an Emission node's colour times strength, a Volume Coefficients node's emission
    coefficients, and a Principled Volume's emission colour times strength plus its
    blackbody (Stefan-Boltzmann radiance mixed by its intensity, tinted). The blackbody's
    hue is left out (grey): what this feeds compares an estimate with the truth, both of
    the same colour. Density does not scale emission."""
    weight = np.asarray(weight, dtype=np.float32)[..., None]
    if node.type == "EMISSION":
        return weight * ev.input(node, "Color", (1.0, 1.0, 1.0)) * ev.input(node, "Strength", 1.0)[..., None]
    if node.type == "VOLUME_COEFFICIENTS":
        return weight * ev.input(node, "Emission Coefficients")
    if node.type != "PRINCIPLED_VOLUME":
        return np.zeros((1, 3), np.float32)
    strength = np.maximum(np.asarray(ev.input(node, "Emission Strength", 0.0)), 0.0)[..., None]
    out = strength * ev.input(node, "Emission Color", (1.0, 1.0, 1.0))
    blackbody = np.maximum(np.asarray(ev.input(node, "Blackbody Intensity", 0.0)), 0.0)
    if np.any(blackbody > 0.0):
        temperature = np.asarray(ev.input(node, "Temperature", 1000.0), np.float64)
        grid = ev.context.grid(node.inputs.get("Temperature Attribute"))
        if grid is not None:
            temperature = temperature * np.maximum(grid if grid.ndim == 1 else grid.mean(axis=1), 0.0)
        t4 = np.maximum(temperature, 0.0) ** 4
        intensity = _BLACKBODY_SIGMA * ((1.0 - blackbody) + blackbody * t4) * (temperature > 0.0)
        out = out + (intensity * (blackbody > 0.0))[..., None] * ev.input(node, "Blackbody Tint", (1.0, 1.0, 1.0))
    return weight * out


def evaluate_extinction(graph: ShaderGraph, context: NodeContext, part: str = "extinction") -> np.ndarray:
    """Extinction coefficients (N, 3) of ``graph`` at ``context.points`` (``part``
    "scattering": their scattering part), finite and >= 0 wherever Cycles would give a
    usable value (NaN counts as no medium, as Cycles' ``fmaxf`` makes it; infinities become
    a very large finite value)."""
    extinction = GraphEvaluator(graph, context).extinction(part)
    return np.nan_to_num(extinction, nan=0.0, posinf=1e30, neginf=-1e30)
