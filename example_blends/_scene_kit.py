"""Shared pieces for the example-scene scripts: an empty Cycles scene, camera, meshes,
materials, volumes and saving.

Everything is built through ``bpy.data`` and ``bmesh`` (no operators that depend on a
window or on the 3D cursor) and nothing is random, so building a scene twice gives the
same content. The scripts use only bpy; they never import the add-on.
"""
from __future__ import annotations

import math
from pathlib import Path

import bpy  # first: the bpy module makes bmesh and mathutils importable
import bmesh
from mathutils import Matrix, Vector

#: Samples per pixel saved in every scene: the ceiling the selective renderer scales.
SAMPLES = 64


# ---------------------------------------------------------------------------------------
# Scene and render settings


def new_scene(name: str, resolution: tuple[int, int], max_bounces: int = 6,
              volume_bounces: int = 1):
    """Start an empty session and set up one Cycles scene for a 512 px render.

    Adaptive sampling and denoising are off so that the sample count alone sets the
    quality (the selective renderer varies it per tile); everything else the paper does
    not speak about keeps Cycles' defaults (light tree on, volume step rate 1).
    """
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.name = name
    scene.frame_start = scene.frame_end = scene.frame_current = 1

    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y = resolution
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False
    r.film_transparent = False
    r.use_persistent_data = False

    c = scene.cycles
    c.device = "CPU"
    c.samples = SAMPLES
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed = 0
    c.use_animated_seed = False
    c.max_bounces = max_bounces
    c.diffuse_bounces = min(4, max_bounces)
    c.glossy_bounces = min(4, max_bounces)
    c.transmission_bounces = max_bounces
    c.transparent_max_bounces = 8
    c.volume_bounces = volume_bounces
    c.use_light_tree = True
    c.volume_step_rate = 1.0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 10.0
    c.caustics_reflective = True
    c.caustics_refractive = True

    v = scene.view_settings
    v.view_transform = "AgX"
    v.look = "None"
    v.exposure = 0.0
    v.gamma = 1.0
    scene.display_settings.display_device = "sRGB"
    return scene


def set_world(scene, color, strength: float = 1.0, fog: dict | None = None):
    """A plain world colour and, when ``fog`` is given, a homogeneous world volume.

    ``fog`` holds Principled Volume settings: density (per scene unit), color,
    anisotropy.
    """
    world = bpy.data.worlds.new("World")
    scene.world = world
    nt = world.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputWorld")
    out.location = (300, 0)
    bg = nt.nodes.new("ShaderNodeBackground")
    bg.name = bg.label = "Sky"
    bg.inputs["Color"].default_value = (*color, 1.0)
    bg.inputs["Strength"].default_value = strength
    nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
    if fog is not None:
        vol = principled_volume_node(nt, name="Fog", **fog)
        vol.location = (0, -200)
        nt.links.new(vol.outputs["Volume"], out.inputs["Volume"])
    return world


# ---------------------------------------------------------------------------------------
# Objects


def link(ob, collection=None):
    (collection or bpy.context.scene.collection).objects.link(ob)
    return ob


def look_at_rotation(location, target, up_axis: str = "Y"):
    """Euler rotation that points an object's -Z axis from ``location`` at ``target``."""
    direction = Vector(target) - Vector(location)
    return direction.to_track_quat("-Z", up_axis).to_euler()


def add_camera(name: str, location, target, lens: float = 35.0, clip_end: float = 200.0):
    cam = bpy.data.cameras.new(name)
    cam.type = "PERSP"
    cam.lens = lens
    cam.sensor_width = 36.0
    cam.sensor_fit = "AUTO"
    cam.clip_start = 0.1
    cam.clip_end = clip_end
    ob = link(bpy.data.objects.new(name, cam))
    ob.location = location
    ob.rotation_euler = look_at_rotation(location, target)
    bpy.context.scene.camera = ob
    return ob


def mesh_object(name: str, build, material=None, location=(0, 0, 0), rotation=(0, 0, 0),
                scale=(1, 1, 1), smooth: bool = False):
    """A mesh object whose geometry ``build(bm)`` makes with bmesh operators."""
    bm = bmesh.new()
    build(bm)
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    if smooth:
        mesh.shade_smooth()
    if material is not None:
        mesh.materials.append(material)
    ob = link(bpy.data.objects.new(name, mesh))
    ob.location, ob.rotation_euler, ob.scale = location, rotation, scale
    return ob


def box(bm, size=(1.0, 1.0, 1.0), center=(0.0, 0.0, 0.0)):
    """An axis-aligned box of the given full size."""
    m = Matrix.Translation(center) @ Matrix.Diagonal((*size, 1.0))
    bmesh.ops.create_cube(bm, size=1.0, matrix=m)


def uv_sphere(radius: float, segments: int = 48, rings: int = 24):
    return lambda bm: bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings,
                                                radius=radius)


def cylinder(radius: float, depth: float, segments: int = 24, center=(0.0, 0.0, 0.0)):
    return lambda bm: bmesh.ops.create_cone(bm, cap_ends=True, segments=segments, radius1=radius,
                                            radius2=radius, depth=depth,
                                            matrix=Matrix.Translation(center))


def disc(radius: float, segments: int = 24, matrix=None):
    """A filled disc in the local XY plane, facing +Z."""
    return lambda bm: bmesh.ops.create_circle(bm, cap_ends=True, segments=segments, radius=radius,
                                              matrix=matrix or Matrix.Identity(4))


def plane(size_x: float, size_y: float, center=(0.0, 0.0, 0.0)):
    def build(bm):
        m = Matrix.Translation(center) @ Matrix.Diagonal((size_x / 2, size_y / 2, 1.0, 1.0))
        bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=1.0, matrix=m)
    return build


def add_light(name: str, kind: str, location, energy: float, color=(1.0, 1.0, 1.0),
              radius: float = 0.1, target=None, rotation=(0, 0, 0), **props):
    """A lamp; ``target`` aims its -Z axis (spot, area, sun), ``props`` sets the rest."""
    light = bpy.data.lights.new(name, kind)
    light.energy = energy
    light.color = color
    if kind in ("POINT", "SPOT"):
        light.shadow_soft_size = radius
    for key, value in props.items():
        setattr(light, key, value)
    ob = link(bpy.data.objects.new(name, light))
    ob.location = location
    ob.rotation_euler = look_at_rotation(location, target) if target is not None else rotation
    return ob


# ---------------------------------------------------------------------------------------
# Materials


def add_street_lamps(lamps, height: float, arm: float, color, energy: float) -> None:
    """Street lamps: for each (number, x, y) a metal pole at (x, y) whose arm reaches ``arm``
    over the road (toward x = 0), a bulb seen by the camera only and the point light inside it
    (``Lamp.N.Pole``, ``Lamp.N.Bulb``, ``Lamp.N``)."""
    metal = surface_material("Lamp Metal", (0.12, 0.12, 0.13), roughness=0.4, metallic=1.0)
    bulb = emission_material("Lamp Bulb", color, strength=25.0)
    for number, x, y in lamps:
        toward_road = -1.0 if x > 0 else 1.0
        head_x = x + toward_road * arm

        def pole(bm, head_x=head_x, x=x, y=y):
            cylinder(0.08, height, segments=12, center=(x, y, height / 2))(bm)
            box(bm, (arm + 0.1, 0.1, 0.1), ((x + head_x) / 2, y, height - 0.05))
            box(bm, (0.5, 0.3, 0.12), (head_x, y, height - 0.1))
        mesh_object(f"Lamp.{number}.Pole", pole, metal)
        seen_by_camera_only(mesh_object(
            f"Lamp.{number}.Bulb", uv_sphere(0.12, 16, 8), bulb,
            location=(head_x, y, height - 0.28), smooth=True))
        add_light(f"Lamp.{number}", "POINT", location=(head_x, y, height - 0.28),
                  energy=energy, color=color, radius=0.12)


def _fresh_tree(material):
    nt = material.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (300, 0)
    out.target = "ALL"
    return nt, out


def surface_material(name: str, color, roughness: float = 0.5, metallic: float = 0.0,
                     specular: float = 0.5, transmission: float = 0.0, ior: float = 1.45,
                     coat: float = 0.0):
    """A Principled BSDF surface."""
    mat = bpy.data.materials.new(name)
    nt, out = _fresh_tree(mat)
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Specular IOR Level"].default_value = specular
    bsdf.inputs["Transmission Weight"].default_value = transmission
    bsdf.inputs["IOR"].default_value = ior
    bsdf.inputs["Coat Weight"].default_value = coat
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    mat.diffuse_color = (*color, 1.0)
    return mat


def emission_material(name: str, color, strength: float):
    """A pure emitter: what a light bulb or a headlight lens looks like from outside."""
    mat = bpy.data.materials.new(name)
    nt, out = _fresh_tree(mat)
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*color, 1.0)
    em.inputs["Strength"].default_value = strength
    nt.links.new(em.outputs["Emission"], out.inputs["Surface"])
    mat.diffuse_color = (*color, 1.0)
    # The lamp next to the emitter lights the scene; the emitter itself is only looked at
    # (see seen_by_camera_only), so next-event estimation should not pick it.
    mat.cycles.emission_sampling = "NONE"
    return mat


def seen_by_camera_only(ob):
    """Show an emissive lens or bulb to the camera, and to nothing else: the point or spot
    light inside it does the lighting (also of the fog), the mesh must not shadow that
    light, and diffuse bounces onto a tiny bright mesh would only add fireflies."""
    ob.visible_diffuse = ob.visible_glossy = ob.visible_transmission = False
    ob.visible_volume_scatter = ob.visible_shadow = False
    return ob


def principled_volume_node(nt, name: str, density: float, color=(1.0, 1.0, 1.0),
                           anisotropy: float = 0.0, absorption_color=(0.0, 0.0, 0.0),
                           density_attribute: str = ""):
    vol = nt.nodes.new("ShaderNodeVolumePrincipled")
    vol.name = vol.label = name
    vol.inputs["Density"].default_value = density
    vol.inputs["Color"].default_value = (*color, 1.0)
    vol.inputs["Anisotropy"].default_value = anisotropy
    vol.inputs["Absorption Color"].default_value = (*absorption_color, 1.0)
    vol.inputs["Density Attribute"].default_value = density_attribute
    return vol


def volume_material(name: str, density: float, color=(1.0, 1.0, 1.0), anisotropy: float = 0.0,
                    density_attribute: str = ""):
    """A material with only a Principled Volume: a medium with no visible boundary."""
    mat = bpy.data.materials.new(name)
    nt, out = _fresh_tree(mat)
    vol = principled_volume_node(nt, "Medium", density, color, anisotropy,
                                 density_attribute=density_attribute)
    nt.links.new(vol.outputs["Volume"], out.inputs["Volume"])
    return mat


# ---------------------------------------------------------------------------------------
# Saving


def save(path: Path) -> Path:
    """Write the session as a compressed .blend (no backup file, no UI, no thumbnails)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    bpy.context.preferences.filepaths.save_version = 0
    bpy.context.preferences.filepaths.use_file_compression = True
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True, relative_remap=True,
                                check_existing=False)
    return path


def degrees(*angles: float) -> tuple[float, ...]:
    return tuple(math.radians(a) for a in angles)
