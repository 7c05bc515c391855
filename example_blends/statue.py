"""statue: the paper's Lucy scene, a detailed statue standing in smoke.

Tests a Blender Volume object as the medium: ``Smoke`` is an object of type VOLUME whose
OpenVDB ``density`` grid is made inside Blender by a geometry-nodes modifier (Volume Cube
filled with a noise field that thins out upwards and away from the statue), so no .vdb
file is needed and the grid is the same on every build. Its material's Principled Volume
reads that grid (Density Attribute ``density``). The statue is Suzanne under a Subdivision Surface
modifier (not applied, so the file stays small) on a plinth; a spot light ``Key`` out of
frame throws a beam through the smoke.

Run: ``python statue.py`` writes statue.blend next to this file.
"""
from __future__ import annotations

from pathlib import Path

import bpy  # first: the bpy module makes bmesh importable
import bmesh

import _scene_kit as kit

NAME = "statue"
RESOLUTION = (384, 512)

#: The smoke's bounds (world space, metres) and voxel counts: 5 cm voxels.
SMOKE_MIN, SMOKE_MAX = (-2.0, -2.0, 0.0), (2.0, 2.0, 3.4)
SMOKE_VOXELS = (80, 80, 68)
#: The smoke column thins out between these distances from the statue's axis.
SMOKE_CORE, SMOKE_RADIUS = 1.5, 2.0
#: Density of the thickest smoke per metre (material Density times the grid's 0..1).
SMOKE_DENSITY = 1.5


def smoke_node_group(material):
    """Geometry nodes: replace the (empty) volume by a Volume Cube whose density is
    smoothstep(noise(position)) * (1 - height / top) * (1 - smoothstep(distance from the
    axis)): a column of patchy smoke around the statue that thins out upwards and has no
    hard edges where the cube ends."""
    ng = bpy.data.node_groups.new("Smoke Grid", "GeometryNodeTree")
    ng.interface.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    ng.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    nodes, links = ng.nodes, ng.links
    nodes.new("NodeGroupInput").location = (-1000, 200)
    out = nodes.new("NodeGroupOutput")
    out.location = (400, 0)

    position = nodes.new("GeometryNodeInputPosition")
    position.location = (-1000, 0)
    noise = nodes.new("ShaderNodeTexNoise")
    noise.name = noise.label = "Smoke Noise"
    noise.location = (-800, 0)
    noise.noise_dimensions = "3D"
    noise.noise_type = "FBM"
    noise.normalize = True
    noise.inputs["Scale"].default_value = 1.1
    noise.inputs["Detail"].default_value = 4.0
    noise.inputs["Roughness"].default_value = 0.6
    noise.inputs["Distortion"].default_value = 0.4
    patches = nodes.new("ShaderNodeMapRange")
    patches.name = patches.label = "Smoke Patches"
    patches.location = (-600, 0)
    patches.interpolation_type = "SMOOTHSTEP"
    patches.clamp = True
    patches.inputs["From Min"].default_value = 0.40
    patches.inputs["From Max"].default_value = 0.65

    height = nodes.new("ShaderNodeSeparateXYZ")
    height.location = (-800, -250)
    fade = nodes.new("ShaderNodeMapRange")
    fade.name = fade.label = "Smoke Fade Upwards"
    fade.location = (-600, -250)
    fade.clamp = True
    fade.inputs["From Min"].default_value = SMOKE_MIN[2]
    fade.inputs["From Max"].default_value = SMOKE_MAX[2]
    fade.inputs["To Min"].default_value = 1.0
    fade.inputs["To Max"].default_value = 0.0
    flat = nodes.new("ShaderNodeVectorMath")
    flat.location = (-800, -450)
    flat.operation = "MULTIPLY"
    flat.inputs[1].default_value = (1.0, 1.0, 0.0)
    axis_distance = nodes.new("ShaderNodeVectorMath")
    axis_distance.location = (-650, -450)
    axis_distance.operation = "LENGTH"
    edge = nodes.new("ShaderNodeMapRange")
    edge.name = edge.label = "Smoke Fade Sideways"
    edge.location = (-500, -450)
    edge.interpolation_type = "SMOOTHSTEP"
    edge.clamp = True
    edge.inputs["From Min"].default_value = SMOKE_CORE
    edge.inputs["From Max"].default_value = SMOKE_RADIUS
    edge.inputs["To Min"].default_value = 1.0
    edge.inputs["To Max"].default_value = 0.0
    density = nodes.new("ShaderNodeMath")
    density.operation = "MULTIPLY"
    density.location = (-400, 0)
    density_sides = nodes.new("ShaderNodeMath")
    density_sides.operation = "MULTIPLY"
    density_sides.location = (-300, -200)

    cube = nodes.new("GeometryNodeVolumeCube")
    cube.location = (-150, 0)
    cube.inputs["Background"].default_value = 0.0
    cube.inputs["Min"].default_value = SMOKE_MIN
    cube.inputs["Max"].default_value = SMOKE_MAX
    for axis, count in zip("XYZ", SMOKE_VOXELS):
        cube.inputs[f"Resolution {axis}"].default_value = count

    links.new(position.outputs["Position"], noise.inputs["Vector"])
    links.new(noise.outputs["Factor"], patches.inputs["Value"])
    links.new(position.outputs["Position"], height.inputs["Vector"])
    links.new(height.outputs["Z"], fade.inputs["Value"])
    links.new(patches.outputs["Result"], density.inputs[0])
    links.new(fade.outputs["Result"], density.inputs[1])
    links.new(position.outputs["Position"], flat.inputs[0])
    links.new(flat.outputs["Vector"], axis_distance.inputs[0])
    links.new(axis_distance.outputs["Value"], edge.inputs["Value"])
    links.new(density.outputs["Value"], density_sides.inputs[0])
    links.new(edge.outputs["Result"], density_sides.inputs[1])
    links.new(density_sides.outputs["Value"], cube.inputs["Density"])
    # A new volume carries no material: give it the smoke's, or Cycles would fall back
    # to its default volume shader and the material on the object would never be used.
    set_material = nodes.new("GeometryNodeSetMaterial")
    set_material.location = (100, 0)
    set_material.inputs["Material"].default_value = material
    links.new(cube.outputs["Volume"], set_material.inputs["Geometry"])
    links.new(set_material.outputs["Geometry"], out.inputs["Geometry"])
    return ng


def add_smoke():
    material = kit.volume_material("Smoke", density=SMOKE_DENSITY, color=(0.7, 0.7, 0.7),
                                   anisotropy=0.3, density_attribute="density")
    volume = bpy.data.volumes.new("Smoke")
    volume.render.space = "OBJECT"
    volume.materials.append(material)
    ob = kit.link(bpy.data.objects.new("Smoke", volume))
    modifier = ob.modifiers.new("Smoke Grid", "NODES")
    modifier.node_group = smoke_node_group(material)
    return ob


def add_statue():
    marble = kit.surface_material("Marble", (0.82, 0.80, 0.76), roughness=0.35)
    stone = kit.surface_material("Plinth", (0.30, 0.29, 0.28), roughness=0.7)
    kit.mesh_object("Plinth", lambda bm: kit.box(bm, (0.8, 0.8, 1.25), (0.0, 0.0, 0.625)), stone)
    statue = kit.mesh_object("Statue", lambda bm: bmesh.ops.create_monkey(bm), marble,
                             location=(0.0, 0.0, 1.86), rotation=kit.degrees(-8.0, 0.0, -20.0),
                             scale=(0.82, 0.82, 0.82), smooth=True)
    subsurf = statue.modifiers.new("Subdivision", "SUBSURF")
    subsurf.levels = 2
    subsurf.render_levels = 3
    subsurf.quality = 3
    return statue


def build():
    scene = kit.new_scene(NAME, RESOLUTION, max_bounces=6, volume_bounces=0)
    kit.set_world(scene, color=(0.02, 0.022, 0.03), strength=1.0)
    floor = kit.surface_material("Floor", (0.35, 0.33, 0.30), roughness=0.8)
    wall = kit.surface_material("Wall", (0.40, 0.40, 0.42), roughness=0.9)
    kit.mesh_object("Floor", kit.plane(12.0, 12.0, center=(0.0, 2.0, 0.0)), floor)
    kit.mesh_object("Wall", kit.plane(12.0, 8.0), wall, location=(0.0, 3.0, 4.0),
                    rotation=kit.degrees(90.0, 0.0, 0.0))
    add_statue()
    add_smoke()
    kit.add_light("Key", "SPOT", location=(-3.5, -2.5, 5.5), target=(0.0, 0.3, 1.4),
                  energy=2200.0, color=(1.0, 0.93, 0.82), radius=0.15,
                  spot_size=kit.degrees(40.0)[0], spot_blend=0.3)
    kit.add_light("Fill", "AREA", location=(3.5, -3.0, 3.0), target=(0.0, 0.0, 1.5),
                  energy=150.0, color=(0.8, 0.87, 1.0), size=2.0)
    kit.add_camera("Camera", location=(0.0, -5.6, 1.9), target=(0.0, 0.0, 1.55), lens=38.0,
                   clip_end=100.0)
    return scene


if __name__ == "__main__":
    build()
    kit.save(Path(__file__).with_name(f"{NAME}.blend"))
