"""Whether anything in a scene may change from frame to frame, and whether its media may.

Conservative: a yes where Blender could change something with the frame (keyframes, drivers,
Geometry Nodes, simulations, image or volume sequences), a no only where nothing can. Auto
Volumes predicts an animated shot at several frames, an unanimated one once, and keeps
Cycles' session between frames (persistent data) only where the media stand still.
"""
from __future__ import annotations

#: Modifiers whose result may change with the frame without keyframes: simulations and
#: physics, waves, caches (Geometry Nodes where its tree reads the time: ``_TIME_NODES``).
_TIME_MODIFIERS = frozenset({"FLUID", "CLOTH", "SOFT_BODY", "DYNAMIC_PAINT", "OCEAN",
                             "WAVE", "PARTICLE_SYSTEM", "EXPLODE", "MESH_CACHE",
                             "MESH_SEQUENCE_CACHE"})


#: Geometry nodes that make a tree's result depend on the frame.
_TIME_NODES = frozenset({"GeometryNodeInputSceneTime", "GeometryNodeSimulationInput",
                         "GeometryNodeSimulationOutput"})


def _keyed(datablock) -> bool:
    data = getattr(datablock, "animation_data", None)
    return data is not None and bool(data.action or len(data.drivers) or len(data.nla_tracks))


def _tree_moves(tree) -> bool:
    """A node tree with keyframes or drivers, the scene's time or a simulation, an image or
    movie sequence, or a group that has."""
    if tree is None:
        return False
    if _keyed(tree):
        return True
    for node in tree.nodes:
        if node.bl_idname in _TIME_NODES:
            return True
        image = getattr(node, "image", None)
        if image is not None and image.source in ("SEQUENCE", "MOVIE"):
            return True
        if getattr(node, "node_tree", None) is not None and _tree_moves(node.node_tree):
            return True
    return False


def _object_moves(ob) -> bool:
    if _keyed(ob) or (ob.data is not None and _keyed(ob.data)) \
            or (ob.parent is not None and _object_moves(ob.parent)):
        return True
    if len(ob.constraints) or any(modifier.type in _TIME_MODIFIERS or (
            modifier.type == "NODES" and _tree_moves(modifier.node_group)) for modifier in ob.modifiers):
        return True
    if ob.type == "VOLUME" and ob.data is not None and ob.data.is_sequence:
        return True
    return any(slot.material is not None and (_keyed(slot.material) or _tree_moves(slot.material.node_tree))
               for slot in ob.material_slots)


def _world_moves(world) -> bool:
    return world is not None and (_keyed(world) or _tree_moves(world.node_tree))


def scene_moves(scene) -> bool:
    """Whether anything the scene renders may change with the frame."""
    return (_keyed(scene) or _world_moves(scene.world)
            or any(marker.camera is not None for marker in scene.timeline_markers)
            or any(_object_moves(ob) for ob in scene.objects))


def _world_medium(world) -> bool:
    from .shader_export import has_volume

    return world is not None and world.node_tree is not None and has_volume(world.node_tree)


def _carries_medium(ob) -> bool:
    from .shader_export import has_volume

    return ob.type == "VOLUME" or any(slot.material is not None and slot.material.node_tree is not None
                                      and has_volume(slot.material.node_tree) for slot in ob.material_slots)


def media_move(scene) -> bool:
    """Whether a participating medium may change with the frame (its object, data, material
    or the world's volume), which makes Cycles rebuild it at every frame anyway."""
    return (_world_medium(scene.world) and _world_moves(scene.world)) \
        or any(_carries_medium(ob) and _object_moves(ob) for ob in scene.objects)


def has_media(scene) -> bool:
    """Whether the scene has a volume anywhere (a material's, a volume object, the world's)."""
    return _world_medium(scene.world) or any(_carries_medium(ob) for ob in scene.objects)
