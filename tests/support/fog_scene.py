"""A small foggy scene for render tests and benchmarks: a ground plane, three spheres, a
homogeneous world fog and two point lights (one in frame, one key light), seen by a
perspective camera. Stands in for the example scenes where a real one is not needed."""
from __future__ import annotations

import math


def build_fog_scene(bpy, width: int = 96, height: int = 54, density: float = 0.05,
                    factory_reset: bool = True):
    """Replace the session with the fog scene at ``width`` x ``height``; return the scene.

    ``factory_reset=False`` keeps the preferences (and so the enabled extensions) and only
    empties the current scene."""
    if factory_reset:
        bpy.ops.wm.read_factory_settings(use_empty=True)
    else:
        for ob in list(bpy.data.objects):
            bpy.data.objects.remove(ob)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    bpy.ops.mesh.primitive_plane_add(size=30)
    for i, x in enumerate((-2.0, 0.0, 2.0)):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.8, location=(x, 2.0 * i, 0.8))
    data = bpy.data.cameras.new("Cam")
    camera = bpy.data.objects.new("Cam", data)
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location, camera.rotation_euler = (0.0, -8.0, 2.0), (math.radians(85), 0.0, 0.0)
    for name, location, energy in (("Lamp", (0.0, 6.0, 2.5), 300.0), ("Key", (3.0, -2.0, 5.0), 500.0)):
        lamp = bpy.data.objects.new(name, bpy.data.lights.new(name, "POINT"))
        lamp.data.energy = energy
        lamp.location = location
        scene.collection.objects.link(lamp)
    world = bpy.data.worlds.new("Fog")
    scene.world = world
    volume = world.node_tree.nodes.new("ShaderNodeVolumePrincipled")
    volume.inputs["Density"].default_value = density
    world.node_tree.links.new(volume.outputs[0], world.node_tree.nodes["World Output"].inputs["Volume"])
    return scene


def saved_fog_scene(folder, width: int, height: int, name: str = "fog.blend"):
    """Build the fog scene in the running bpy session and save it as ``folder/name``; returns
    the path (for module-scoped fixtures of command-line tests)."""
    import bpy

    path = folder / name
    build_fog_scene(bpy, width, height)
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def radial_map(width: int, height: int, mean: float, floor: float = 0.02):
    """A synthetic director map: a Gaussian blob in the middle of the frame on a low floor,
    its width chosen (by bisection) so that the map's mean is ``mean``. A test input only."""
    import numpy as np

    rows, cols = np.mgrid[0:height, 0:width].astype(np.float64)
    dist2 = ((rows + 0.5 - height / 2) ** 2 + (cols + 0.5 - width / 2) ** 2) / max(width, height) ** 2

    def blob(sigma):
        return floor + (1.0 - floor) * np.exp(-dist2 / (2.0 * sigma * sigma))

    low, high = 1e-4, 10.0
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if blob(mid).mean() < mean else (low, mid)
    return blob(0.5 * (low + high)).astype(np.float32)
