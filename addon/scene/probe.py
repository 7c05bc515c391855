"""Turn a Blender scene into plain data: the camera model, the media and the light sources.

Read-only: nothing here changes the scene. The results are the dataclasses of
``core.media.scene_model`` and ``core.camera.CameraModel``, which the bpy-free core consumes.
"""
from __future__ import annotations

import math

import numpy as np

from ...core.camera import CameraModel
from ...core.checks import fits_in_memory
from ...core.errors import InputError
from ...core.media.scene_model import (VOLUME_NODE_TYPES, LightSource, Medium, VolumeClosure,
                                       closure_extinction)

# ---------------------------------------------------------------------------------------
# Camera


def render_size(scene) -> tuple[int, int]:
    """Output size in pixels: the resolution scaled by the percentage, as Blender renders;
    InputError for a size that cannot fit in memory (a scene set to 65536 x 65536, say)."""
    r = scene.render
    return fits_in_memory(max(1, int(r.resolution_x * r.resolution_percentage / 100)),
                          max(1, int(r.resolution_y * r.resolution_percentage / 100)),
                          f"scene '{scene.name}' renders at")


def camera_model(scene, size: tuple[int, int] | None = None, respect_border: bool = True) -> CameraModel:
    """The scene's active camera as a CameraModel at the render size (or ``size``)."""
    cam_ob = scene.camera
    if cam_ob is None:
        raise InputError(f"scene '{scene.name}' has no active camera")
    if cam_ob.type != "CAMERA":
        raise InputError(f"the active camera '{cam_ob.name}' of scene '{scene.name}' is not a camera object")
    cam = cam_ob.data
    width, height = size or render_size(scene)
    r = scene.render
    border = None
    if respect_border and r.use_border:
        border = (r.border_min_x, r.border_min_y, r.border_max_x, r.border_max_y)
    return CameraModel(
        kind=cam.type, matrix_world=np.array(cam_ob.matrix_world, dtype=np.float64),
        width=width, height=height, lens=cam.lens, sensor_width=cam.sensor_width,
        sensor_height=cam.sensor_height, sensor_fit=cam.sensor_fit, ortho_scale=cam.ortho_scale,
        shift_x=cam.shift_x, shift_y=cam.shift_y, clip_start=cam.clip_start, clip_end=cam.clip_end,
        pixel_aspect_x=r.pixel_aspect_x, pixel_aspect_y=r.pixel_aspect_y, border=border,
        name=cam_ob.name)


# ---------------------------------------------------------------------------------------
# Shader graphs


def linked_from(socket):
    """The output socket feeding ``socket`` (skipping reroutes and muted links), or None."""
    for link in socket.links:
        if link.is_muted:
            continue
        node = link.from_node
        if node.type == "REROUTE":
            return linked_from(node.inputs[0])
        return link.from_socket
    return None


def _value(socket):
    """A socket's constant value (float or RGB tuple), or None when something drives it."""
    if linked_from(socket) is not None:
        return None
    value = socket.default_value
    try:
        return tuple(float(v) for v in value)[:3]
    except TypeError:
        return float(value)


def _driver_name(socket) -> str | None:
    source = linked_from(socket)
    return None if source is None else f"{source.node.type}:{source.node.name}"


def walk_shader(output_socket, weight: float | None = 1.0, depth: int = 0):
    """Yield (node, weight) for every shader node that ``output_socket`` sums up.

    Follows Add Shader (weights 1 and 1), Mix Shader (1 - fac and fac; a driven factor
    makes the weight None) and node groups. Muted nodes pass nothing.
    """
    if output_socket is None or depth > 64:
        return
    node = output_socket.node
    if node.mute:
        return
    if node.type == "ADD_SHADER":
        for socket in node.inputs:
            yield from walk_shader(linked_from(socket), weight, depth + 1)
    elif node.type == "MIX_SHADER":
        fac = _value(node.inputs[0])
        for socket, w in ((node.inputs[1], None if fac is None else 1.0 - fac),
                          (node.inputs[2], fac)):
            if w == 0.0:
                continue
            yield from walk_shader(linked_from(socket),
                                   None if weight is None or w is None else weight * w, depth + 1)
    elif node.type == "GROUP" and node.node_tree is not None:
        inner_out = next((n for n in node.node_tree.nodes
                          if n.type == "GROUP_OUTPUT" and n.is_active_output), None)
        if inner_out is not None:
            index = list(node.outputs).index(output_socket)
            yield from walk_shader(linked_from(inner_out.inputs[index]), weight, depth + 1)
    else:
        yield node, weight


def output_shader(node_tree, name: str):
    """The socket feeding the Cycles output node's ``name`` input ("Surface", "Volume"), or None."""
    if node_tree is None:
        return None
    output = node_tree.get_output_node("CYCLES")
    if output is None or name not in output.inputs:
        return None
    return linked_from(output.inputs[name])


def volume_closures(node_tree, grid_names: tuple[str, ...] = ()) -> list[VolumeClosure]:
    """The volume closures feeding the Volume output of a material or world node tree."""
    closures = []
    for node, weight in walk_shader(output_shader(node_tree, "Volume")):
        if node.type not in VOLUME_NODE_TYPES:
            continue
        density = _value(node.inputs["Density"]) if "Density" in node.inputs else 1.0
        driver = _driver_name(node.inputs["Density"]) if "Density" in node.inputs else None
        color = _value(node.inputs["Color"]) if "Color" in node.inputs else (1.0, 1.0, 1.0)
        absorption = (_value(node.inputs["Absorption Color"])
                      if "Absorption Color" in node.inputs else (0.0, 0.0, 0.0))
        if node.type == "PRINCIPLED_VOLUME" and grid_names:
            # On volume objects Cycles multiplies density by the grid the node names.
            attribute = node.inputs["Density Attribute"].default_value if "Density Attribute" in node.inputs else ""
            if attribute in grid_names:
                driver = f"grid:{attribute}" if driver is None else f"{driver}*grid:{attribute}"
        coefficients = {}
        if node.type == "VOLUME_COEFFICIENTS":
            coefficients = {"absorption_coefficients": _value(node.inputs["Absorption Coefficients"]),
                            "scatter_coefficients": _value(node.inputs["Scatter Coefficients"])}
        constant = (driver is None and density is not None and color is not None
                    and absorption is not None and None not in coefficients.values())
        extinction = closure_extinction(node.type, density, color, absorption, **coefficients) if constant else None
        closures.append(VolumeClosure(
            node_type=node.type, node_name=node.name, weight=weight,
            density=None if driver else density, density_driver=driver, color=color,
            absorption_color=absorption if node.type == "PRINCIPLED_VOLUME" else None,
            extinction=extinction))
    return closures


# ---------------------------------------------------------------------------------------
# Media


def _world_bbox(ob, matrix) -> tuple[tuple, tuple]:
    corners = np.array([tuple(c) for c in ob.bound_box], dtype=np.float64)
    world = corners @ np.array(matrix, dtype=np.float64)[:3, :3].T + np.array(matrix)[:3, 3]
    return tuple(world.min(axis=0).tolist()), tuple(world.max(axis=0).tolist())


def renderable_instances(depsgraph):
    """(evaluated object, world matrix) of everything that renders: instances included,
    objects hidden from the render left out, and geometry hidden from camera rays too.

    Lamps are kept whatever their camera visibility (Blender turns it off for new lights):
    a lamp the camera cannot see directly still lights up the fog around it.
    """
    for inst in depsgraph.object_instances:
        ob = inst.object
        if ob.original.hide_render:
            continue
        if ob.type != "LIGHT" and not getattr(ob, "visible_camera", True):
            continue
        yield ob, inst.matrix_world.copy()


def find_media(scene, depsgraph) -> list[Medium]:
    """Every participating medium: the world volume and objects with volume shaders."""
    media = []
    world = scene.world
    if world is not None and world.node_tree is not None:
        closures = volume_closures(world.node_tree)
        if closures:
            media.append(Medium(name=world.name, kind="world", material=None, closures=closures))
    for ob, matrix in renderable_instances(depsgraph):
        if ob.type not in ("MESH", "VOLUME"):
            continue
        grids = ()
        if ob.type == "VOLUME":
            ob.data.grids.load()
            grids = tuple(g.name for g in ob.data.grids)
        for slot in ob.material_slots:
            material = slot.material
            if material is None:
                continue
            closures = volume_closures(material.node_tree, grids)
            if not closures:
                continue
            lo, hi = _world_bbox(ob, matrix)
            media.append(Medium(name=ob.name, kind="volume_object" if ob.type == "VOLUME" else "mesh",
                                material=material.name, closures=closures, bbox_min=lo, bbox_max=hi))
    return media


# ---------------------------------------------------------------------------------------
# Lights


def surface_emission(node_tree) -> tuple[tuple, float] | None:
    """(colour, strength) of the emission a surface shader adds, or None.

    A driven strength or colour counts as emissive with the socket's own value."""
    best = None
    for node, weight in walk_shader(output_shader(node_tree, "Surface")):
        if node.type == "EMISSION":
            color_socket, strength_socket = node.inputs["Color"], node.inputs["Strength"]
        elif node.type == "BSDF_PRINCIPLED":
            color_socket, strength_socket = node.inputs["Emission Color"], node.inputs["Emission Strength"]
        else:
            continue
        color = tuple(color_socket.default_value)[:3]
        strength = float(strength_socket.default_value) * (1.0 if weight is None else weight)
        driven = linked_from(strength_socket) is not None or linked_from(color_socket) is not None
        if not driven and (strength <= 0.0 or max(color) <= 0.0):
            continue
        if best is None or strength > best[1]:
            best = (color, strength)
    return best


def find_lights(scene, depsgraph, camera: CameraModel | None = None) -> list[LightSource]:
    """Lamps and emissive meshes, each flagged with whether it can show in the frame."""
    lights = []
    for ob, matrix in renderable_instances(depsgraph):
        m = np.array(matrix, dtype=np.float64)
        location = tuple(m[:3, 3].tolist())
        if ob.type == "LIGHT":
            light = ob.data
            z = m[:3, 2] / max(np.linalg.norm(m[:3, 2]), 1e-12)
            kind = light.type
            entry = LightSource(
                name=ob.name, kind=kind, location=location, direction=tuple((-z).tolist()),
                size=float(light.angle if kind == "SUN" else
                           light.size if kind == "AREA" else light.shadow_soft_size),
                color=tuple(light.color), energy=float(light.energy))
            if kind == "SPOT":
                entry.spot_size, entry.spot_blend = float(light.spot_size), float(light.spot_blend)
            if kind == "AREA":
                entry.shape = light.shape
                entry.size_y = float(light.size_y) if light.shape in ("RECTANGLE", "ELLIPSE") else float(light.size)
            lights.append(entry)
        elif ob.type == "MESH":
            for slot in ob.material_slots:
                if slot.material is None:
                    continue
                found = surface_emission(slot.material.node_tree)
                if found is None:
                    continue
                lo, hi = (np.array(v) for v in _world_bbox(ob, matrix))
                lights.append(LightSource(
                    name=ob.name, kind="MESH", location=tuple(((lo + hi) / 2).tolist()),
                    direction=(0.0, 0.0, 0.0), size=float(np.linalg.norm(hi - lo) / 2),
                    color=tuple(float(c) for c in found[0]), energy=found[1],
                    extra={"material": slot.material.name}))
                break
    if camera is not None:
        for entry in lights:
            entry.in_frame = light_in_frame(camera, entry)
    return lights


def light_in_frame(camera: CameraModel, light: LightSource) -> bool:
    """Whether a light source (with its size) projects into the frame."""
    if light.kind == "SUN":
        toward_sun = -np.asarray(light.direction)
        far = camera.eye + toward_sun * 0.5 * (camera.clip_start + camera.clip_end)
        half_angle = 0.5 * light.size
        if camera.kind == "ORTHO":
            return False          # a sun disc is at infinity; an orthographic camera never sees it
        return bool(camera.in_frame(far[None], margin_px=_angle_to_px(camera, half_angle))[0])
    point = np.asarray(light.location)[None]
    _, _, depth = camera.project(point)
    if depth[0] <= 0:
        return False
    margin = light.size / float(camera.pixel_size_at(max(depth[0], 1e-6)))
    col, row, _ = camera.project(point)
    inside = (-margin <= col[0] <= camera.width + margin) and (-margin <= row[0] <= camera.height + margin)
    near, far = camera.clip_start - light.size, camera.clip_end + light.size
    return bool(inside and near < depth[0] < far)


def _angle_to_px(camera: CameraModel, angle: float) -> float:
    xmin, xmax, _, _, distance = camera.view_plane()
    return math.tan(angle) * distance / ((xmax - xmin) / camera.width)


# ---------------------------------------------------------------------------------------
# Everything at once


def describe_scene(scene, depsgraph) -> dict:
    """What ``xsl-render info`` reports: camera, render settings, media, lights, frames."""
    camera = camera_model(scene, respect_border=False)
    cam = scene.camera.data
    width, height = render_size(scene)
    media = find_media(scene, depsgraph)
    lights = find_lights(scene, depsgraph, camera)
    r = scene.render
    return {
        "scene": scene.name,
        "camera": {
            "name": scene.camera.name, "type": cam.type, "lens_mm": cam.lens,
            "sensor_width_mm": cam.sensor_width, "sensor_height_mm": cam.sensor_height,
            "sensor_fit": cam.sensor_fit, "ortho_scale": cam.ortho_scale,
            "shift": [cam.shift_x, cam.shift_y], "clip_start": cam.clip_start, "clip_end": cam.clip_end,
            "location": list(camera.eye), "view_direction": list(camera.view_axis()),
        },
        "render": {
            "engine": r.engine, "resolution": [width, height],
            "resolution_setting": [r.resolution_x, r.resolution_y, r.resolution_percentage],
            "samples": scene.cycles.samples if hasattr(scene, "cycles") else None,
            "border": [r.border_min_x, r.border_min_y, r.border_max_x, r.border_max_y] if r.use_border else None,
        },
        "media": [m.to_dict() for m in media],
        "lights": [light.to_dict() for light in lights if light.in_frame],
        "lights_out_of_frame": [light.name for light in lights if not light.in_frame],
        "frames": {"start": scene.frame_start, "end": scene.frame_end, "step": scene.frame_step,
                   "current": scene.frame_current, "fps": scene.render.fps / scene.render.fps_base},
    }
