"""Cycles measures the transmittance itself: the truth for tests, and the fallback for media
numpy cannot evaluate.

Every surface emits exactly 1 and nothing else lights anything (lamps hidden, world black,
no bounces); each volume shader becomes a Volume Absorption of the same extinction fed by the
same density links (so Cycles evaluates textures and grids its own way). Every pixel is then
exp(-tau) to its first surface, per channel; the smallest Blackman-Harris filter sends every
sample through the pixel's centre, as the X map's rays go. Materials, node groups and the
world are copied for the render, assigned to object-linked slots (which override what
geometry nodes set), and everything is put back."""
from __future__ import annotations

import time
from contextlib import contextmanager

import numpy as np

from ...core.maps.embree_ties import ORACLE_FILTER_WIDTH
from ...core.media.volume_medium import VolumeMedium
from ..cycles.render import render_passes
from ..scene.shader_export import has_surface, has_volume, output_socket_input
from ..scene.state import preserved_scene

_MESH_LIKE = ("MESH", "CURVE", "SURFACE", "FONT", "META")


#: Cycles' volume step rate for the oracle's ray marching (1 = Cycles' own step size).
ORACLE_STEP_RATE = 0.05


def render_transmittance(scene, include: list[VolumeMedium] | None = None, samples: int = 16,
                         scale: float = 1.0, step_rate: float = ORACLE_STEP_RATE,
                         sky: float = 0.0, resize: bool = True,
                         window: tuple[int, int, int, int] | None = None, seed: int = 0,
                         ) -> tuple[np.ndarray, float]:
    """Render exp(-tau) per channel for the whole frame: (H, W, 3) float32, row 0 on top
    (or only ``window``).

    Parameters
    ----------
    scene : bpy.types.Scene
    include : list of VolumeMedium, optional
        The media to keep (by object and material slot, and the world); the others are
        removed for this render. None keeps every medium.
    samples : int
        Cycles samples per pixel (absorption-only media converge fast).
    scale : float
        Render at this fraction of the resolution (the cheap fallback for volumes numpy
        cannot evaluate) and, with ``resize``, interpolate to full size; without, the
        low-resolution render is returned (``core.maps.guided_upsample`` does better at edges).
    step_rate : float
        Cycles' volume step rate. The oracle ray-marches (Cycles' "biased" volume mode):
        with an absorbing medium each sample is then a deterministic quadrature of the
        optical depth, nearly noise-free, and a small step rate makes it exact. Cycles'
        default null scattering estimates the same expectation but, measured on a
        noise-textured fog, needed 30 s and still left 0.005 of noise where marching at
        rate 0.05 took 3 s and agreed with numpy to 0.0007.
    sky : float
        Emission of the world background: 0 (the oracle proper: only surfaces count) or 1,
        so rays that hit nothing measure the transmittance to infinity, which keeps a
        resized low-resolution render from smearing black sky into the horizon.
    window : (row0, row1, col0, col1), optional
        Render only these pixels of the frame (rows from the top, half-open), as a
        render border cropped to them; the result is the window's size. Only at
        ``scale`` 1.
    seed : int
        Cycles' sampling seed.

    Returns
    -------
    (transmittance, seconds)
    """
    start = time.perf_counter()
    if window is not None and scale != 1.0:
        raise ValueError("a window of the frame renders at full resolution only")
    with oracle_scene(scene, include, samples, scale, step_rate, sky, seed):
        if window is not None:
            _border_on(scene, window)
        passes = render_passes(scene, ("Combined",))
    rgb = passes["Combined"][:, :, :3]
    if window is not None:
        return np.clip(rgb, 0.0, None).astype(np.float32), time.perf_counter() - start
    height, width = _full_size(scene)
    if resize and rgb.shape[:2] != (height, width):
        from skimage.transform import resize

        rgb = resize(rgb, (height, width, 3), order=1, mode="edge", anti_aliasing=False)
    return np.clip(rgb, 0.0, None).astype(np.float32), time.perf_counter() - start


@contextmanager
def oracle_scene(scene, include: list[VolumeMedium] | None = None, samples: int = 16,
                 scale: float = 1.0, step_rate: float = ORACLE_STEP_RATE, sky: float = 0.0,
                 seed: int = 0):
    """The scene set up as the oracle renders it (see ``render_transmittance`` for the
    parameters), for the duration of the block; everything is put back afterwards.
    Render passes inside it with ``cycles_render.render_passes``."""
    import bpy

    with preserved_scene(scene) as state, _temporary_slots() as add_slot:
        _oracle_settings(scene, samples, scale, step_rate, seed)
        keep_world = include is None or any(m.kind == "world" for m in include)
        keep_slots = None if include is None else {
            (m.name, int(m.key.rsplit(":", 1)[1])) for m in include if m.kind != "world"}
        factory = _OracleMaterials(scene)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        for ob in _scene_objects(scene, depsgraph):
            if ob.type == "LIGHT":
                ob.hide_render = True
                continue
            if not hasattr(ob, "material_slots") or ob.type in ("CAMERA", "EMPTY"):
                continue
            if not ob.material_slots and ob.type in _MESH_LIKE and ob.data is not None:
                add_slot(ob.data, factory.emission())
                continue
            grids = _grid_names(ob, depsgraph)
            rendered = _rendered_materials(ob, depsgraph)
            for index, slot in enumerate(ob.material_slots):
                keep = keep_slots is None or (ob.name, index) in keep_slots
                # The copy replaces what Cycles renders in this slot: the evaluated
                # geometry's material (geometry nodes may set it) unless the slot is the
                # object's own; an object-linked copy overrides either.
                material = rendered.get(index, slot.material)
                state.swap_material(ob, index, factory.copy(material, keep, grids), link="OBJECT")
        scene.world = factory.world(scene.world, keep_world, sky)
        yield scene


def _border_on(scene, window) -> None:
    """Render only ``window`` of the frame, cropped (inside ``oracle_scene``, which puts
    the settings back)."""
    from ...core.camera import border_for_window

    height, width = _full_size(scene)
    r = scene.render
    r.use_border, r.use_crop_to_border = True, True
    r.border_min_x, r.border_min_y, r.border_max_x, r.border_max_y = border_for_window(
        window, width, height)


def _scene_objects(scene, depsgraph) -> list:
    """The scene's objects plus the originals of everything instanced into it."""
    objects = {ob.name: ob for ob in scene.objects}
    for instance in depsgraph.object_instances:
        original = instance.object.original
        objects.setdefault(original.name, original)
    return list(objects.values())


def _full_size(scene) -> tuple[int, int]:
    from ..scene.probe import render_size

    width, height = render_size(scene)
    return height, width


def _rendered_materials(ob, depsgraph) -> dict:
    """Material per slot index of the evaluated object (what Cycles renders)."""
    evaluated = ob.evaluated_get(depsgraph)
    return {index: slot.material for index, slot in enumerate(evaluated.material_slots)}


def _grid_names(ob, depsgraph) -> frozenset:
    """Grids of the evaluated volume (geometry nodes may create them at evaluation)."""
    if ob.type != "VOLUME":
        return frozenset()
    data = ob.evaluated_get(depsgraph).data
    data.grids.load()
    return frozenset(grid.name for grid in data.grids)


def _oracle_settings(scene, samples: int, scale: float, step_rate: float, seed: int = 0) -> None:
    from ..cycles.render import ensure_cycles

    ensure_cycles(scene)
    c = scene.cycles
    c.samples = max(1, int(samples))
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = seed
    c.use_animated_seed = False
    c.max_bounces = 0
    for name in ("diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces"):
        setattr(c, name, 0)
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.pixel_filter_type = "BLACKMAN_HARRIS"   # a box filter ignores the width
    c.filter_width = ORACLE_FILTER_WIDTH
    c.film_exposure = 1.0
    c.volume_biased = True
    c.volume_step_rate = step_rate
    c.volume_max_steps = 65536
    r = scene.render
    r.film_transparent = False
    r.use_motion_blur = False
    r.use_crop_to_border = False
    if scale != 1.0:
        r.resolution_percentage = max(1, int(round(r.resolution_percentage * scale)))


@contextmanager
def _temporary_slots():
    """Give slot-less meshes an emission material for the render; take it away after."""
    added = []

    def add(data, material):
        if all(d != data for d in added):
            data.materials.append(material)
            added.append(data)

    try:
        yield add
    finally:
        for data in added:
            # Only data that had no material gets one, so clearing restores it exactly
            # (``pop`` would leave the object an empty slot behind).
            data.materials.clear()


class _OracleMaterials:
    """Makes (and reuses) the oracle copies of materials and the world."""

    def __init__(self, scene):
        import bpy

        self.bpy = bpy
        self._copies: dict = {}
        self._emission = None

    def emission(self):
        if self._emission is None:
            material = self.bpy.data.materials.new("xsl oracle emission")
            tree = material.node_tree
            tree.nodes.clear()
            output = tree.nodes.new("ShaderNodeOutputMaterial")
            _emit_one(tree, output)
            self._emission = material
        return self._emission

    def copy(self, material, keep_volume: bool, grids: frozenset):
        if material is None or material.node_tree is None:
            return self.emission()
        key = (material.name, keep_volume, grids)
        if key not in self._copies:
            copy = material.copy()
            copy.name = f"xsl oracle {material.name}"
            tree = copy.node_tree
            output = tree.get_output_node("CYCLES")
            if output is None:
                output = tree.nodes.new("ShaderNodeOutputMaterial")
                output.is_active_output = True
            if has_surface(material):
                _emit_one(tree, output)
            if hasattr(copy, "cycles"):
                copy.cycles.emission_sampling = "NONE"
                copy.cycles.volume_step_rate = 1.0
            _absorption_only(tree, output, keep_volume, grids)
            self._copies[key] = copy
        return self._copies[key]

    def world(self, world, keep_volume: bool, sky: float = 0.0):
        copy = (world.copy() if world is not None else self.bpy.data.worlds.new("xsl oracle world"))
        copy.name = "xsl oracle world"
        tree = copy.node_tree
        if tree is None:
            return copy
        output = tree.get_output_node("CYCLES")
        if output is None:
            return copy
        surface = output_socket_input(tree, "Surface")
        for link in list(surface.links if surface is not None else ()):
            tree.links.remove(link)           # an unlinked world surface renders black
        if sky > 0.0 and surface is not None:
            background = tree.nodes.new("ShaderNodeBackground")
            background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
            background.inputs["Strength"].default_value = sky
            tree.links.new(background.outputs[0], surface)
        _absorption_only(tree, output, keep_volume and has_volume(tree), frozenset())
        return copy


def _emit_one(tree, output) -> None:
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    emission.inputs["Strength"].default_value = 1.0
    tree.links.new(emission.outputs[0], output_socket_input(tree, "Surface"))


# ---------------------------------------------------------------------------------------
# Rewiring volume shaders into absorption with the same extinction

def _absorption_only(tree, output, keep: bool, grids: frozenset) -> None:
    socket = output_socket_input(tree, "Volume")
    if socket is None:
        return
    if not keep:
        for link in list(socket.links):
            tree.links.remove(link)
        return
    for node_tree, node in _volume_closures(tree, socket):
        _replace_closure(node_tree, node, grids)


def _volume_closures(tree, socket, depth=0):
    """(tree, node) of every shader node summed into ``socket``; node groups on the way are
    replaced by private copies first, so rewiring them never touches the user's groups."""
    found = []
    if depth > 64:
        return found
    for link in list(socket.links):
        if link.is_muted:
            continue
        node = link.from_node
        if node.type == "REROUTE":
            found += _volume_closures(tree, node.inputs[0], depth + 1)
        elif node.type in ("ADD_SHADER", "MIX_SHADER"):
            for child in node.inputs:
                if child.type == "SHADER":
                    found += _volume_closures(tree, child, depth + 1)
        elif node.type == "GROUP" and node.node_tree is not None:
            node.node_tree = node.node_tree.copy()
            inner = next((n for n in node.node_tree.nodes
                          if n.type == "GROUP_OUTPUT" and n.is_active_output), None)
            if inner is not None:
                target = next(s for s in inner.inputs if s.identifier == link.from_socket.identifier)
                found += _volume_closures(node.node_tree, target, depth + 1)
        elif not node.mute:
            found.append((tree, node))
    return found


def _source(socket):
    """The output feeding ``socket``, or None (then its default_value is what counts)."""
    for link in socket.links:
        if not link.is_muted:
            return link.from_socket
    return None


def _feed(tree, source, default, target) -> None:
    """Connect ``source`` (an output socket) to ``target``, or copy the constant."""
    if source is not None:
        tree.links.new(source, target)
    else:
        value = default
        if hasattr(target.default_value, "__len__") and not hasattr(value, "__len__"):
            value = (value,) * len(target.default_value)
        elif hasattr(target.default_value, "__len__") and len(value) != len(target.default_value):
            value = tuple(value)[:3] + (1.0,) * (len(target.default_value) - 3)
        target.default_value = value


def _vector_math(tree, operation, a, b):
    """A Vector Math node computing ``a op b``; a and b are (output socket | constant)."""
    node = tree.nodes.new("ShaderNodeVectorMath")
    node.operation = operation
    for operand, socket in ((a, node.inputs[0]), (b, node.inputs[1])):
        if isinstance(operand, tuple):
            socket.default_value = operand
        else:
            tree.links.new(operand, socket)
    return node.outputs["Vector"]


def _input(node, name):
    source = _source(node.inputs[name])
    if source is not None:
        return source
    return tuple(node.inputs[name].default_value)[:3]


def _replace_closure(tree, node, grids: frozenset) -> None:
    outputs = [link.to_socket for link in node.outputs[0].links]
    if node.type == "VOLUME_ABSORPTION":
        return
    if node.type == "VOLUME_COEFFICIENTS":
        total = _vector_math(tree, "ADD", _input(node, "Absorption Coefficients"),
                             _input(node, "Scatter Coefficients"))
        tree.links.new(total, node.inputs["Absorption Coefficients"])
        for name in ("Scatter Coefficients", "Emission Coefficients"):
            for link in list(node.inputs[name].links):
                tree.links.remove(link)
            node.inputs[name].default_value = (0.0, 0.0, 0.0)
        return
    if node.type not in ("VOLUME_SCATTER", "PRINCIPLED_VOLUME"):
        # Emission (or anything else) plugged into a Volume output adds light, no
        # extinction: drop it.
        for link in list(node.outputs[0].links):
            tree.links.remove(link)
        return
    absorption = tree.nodes.new("ShaderNodeVolumeAbsorption")
    absorption.location = node.location
    density_source = _source(node.inputs["Density"])
    density_default = node.inputs["Density"].default_value
    color = _input(node, "Color")
    if node.type == "PRINCIPLED_VOLUME":
        density_attribute = node.inputs["Density Attribute"].default_value
        color_attribute = node.inputs["Color Attribute"].default_value
        if density_attribute and density_attribute in grids:
            # On a volume object Cycles multiplies the density by the grid of that name.
            grid = tree.nodes.new("ShaderNodeAttribute")
            grid.attribute_name = density_attribute
            product = tree.nodes.new("ShaderNodeMath")
            product.operation = "MULTIPLY"
            _feed(tree, density_source, density_default, product.inputs[0])
            tree.links.new(grid.outputs["Fac"], product.inputs[1])
            density_source = product.outputs[0]
        if color_attribute and color_attribute in grids:
            grid = tree.nodes.new("ShaderNodeAttribute")
            grid.attribute_name = color_attribute
            color = _vector_math(tree, "MULTIPLY", color, grid.outputs["Color"])
        # Cycles: colour + max(1 - colour, 0) * max(1 - sqrt(absorption colour), 0).
        root = _vector_math(tree, "POWER", _input(node, "Absorption Color"), (0.5, 0.5, 0.5))
        keep = _vector_math(tree, "MAXIMUM", _vector_math(tree, "SUBTRACT", (1.0, 1.0, 1.0), root),
                            (0.0, 0.0, 0.0))
        rest = _vector_math(tree, "MAXIMUM", _vector_math(tree, "SUBTRACT", (1.0, 1.0, 1.0), color),
                            (0.0, 0.0, 0.0))
        unit = _vector_math(tree, "ADD", color, _vector_math(tree, "MULTIPLY", rest, keep))
    else:
        unit = color                     # Volume Scatter: extinction density * colour
    # Volume Absorption's extinction is density * (1 - colour): feed it 1 - unit.
    tree.links.new(_vector_math(tree, "SUBTRACT", (1.0, 1.0, 1.0), unit),
                   absorption.inputs["Color"])
    _feed(tree, density_source, density_default, absorption.inputs["Density"])
    for target in outputs:
        tree.links.new(absorption.outputs[0], target)
    tree.nodes.remove(node)
