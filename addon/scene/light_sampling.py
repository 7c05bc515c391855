"""What Cycles samples as lights in a scene, for auto's light-tree choice
(``core.sampling.light_tree``).

Counted as Cycles counts them (checked against its renders in ``tests/test_light_tree.py``):
every lamp that renders; every polygon of a surface whose material emits and whose emission
sampling is not None (a mesh light is one light per triangle); the world where its background
varies over directions and its sampling method is not None. Where it cannot tell (a node
group's output, a script node, a driven mix), it counts a light, so that auto keeps the tree.
"""
from __future__ import annotations

from .probe import linked_from, output_shader, surface_emission, walk_shader

#: Object types Cycles renders as surfaces (each may carry an emissive material).
_SURFACE_TYPES = ("MESH", "CURVE", "SURFACE", "META", "FONT", "CURVES", "POINTCLOUD")


def sampled_lights(scene, depsgraph) -> int:
    """How many lights Cycles' light sampling chooses among (2 stands for "several")."""
    count = int(world_is_sampled(scene.world))
    for inst in depsgraph.object_instances:
        ob = inst.object
        if ob.original.hide_render:
            continue
        if ob.type == "LIGHT":
            count += 1
        elif ob.type in _SURFACE_TYPES and any(emits_sampled_light(slot.material) for slot in ob.material_slots):
            polygons = len(ob.data.polygons) if ob.type == "MESH" else 2
            count += max(polygons, 1)
        if count > 1:
            return count
    return count


def links_lights(scene) -> bool:
    """Whether any object links lights (Blender's light and shadow linking)."""
    return any(ob.light_linking.receiver_collection is not None
               or ob.light_linking.blocker_collection is not None
               for ob in scene.objects if hasattr(ob, "light_linking"))


def world_is_sampled(world) -> bool:
    """Whether Cycles samples the world as a light: its sampling method is not None and its
    background is not one constant colour."""
    if world is None or world.cycles.sampling_method == "NONE" or world.node_tree is None:
        return False
    for node, weight in walk_shader(output_shader(world.node_tree, "Surface")):
        constant = (node.type == "BACKGROUND" and weight is not None
                    and all(linked_from(socket) is None for socket in node.inputs))
        if not constant:
            return True
    return False


def emits_sampled_light(material) -> bool:
    """Whether Cycles samples ``material``'s surface as a light."""
    if material is None or material.node_tree is None or material.cycles.emission_sampling == "NONE":
        return False
    if surface_emission(material.node_tree) is not None:
        return True
    return any(node.type == "SCRIPT" for node, _ in walk_shader(output_shader(material.node_tree, "Surface")))
