"""balls B: the balls A room in thicker, heterogeneous fog.

Tests the heterogeneous case of the X map: the fog box ``Fog`` has a Principled Volume
whose Density is driven by a Noise Texture (through Map Range and a Multiply), evaluated in
the box's own Object coordinates, so the density field is fixed in space and the same on
every build and every render. The X map has to ray-march it.

Run: ``python balls_b.py`` writes balls_b.blend next to this file.
"""
from __future__ import annotations

from pathlib import Path

import bpy

import _scene_kit as kit
from balls_a import RESOLUTION, add_fog_box, build_room

NAME = "balls_b"

#: Density where the noise is thickest, per metre; the mean over the box is about a third.
PEAK_DENSITY = 0.6
#: Noise values mapped to density 0 and PEAK_DENSITY: below the first the air is clear,
#: which gives the fog its patches.
NOISE_CLEAR, NOISE_THICK = 0.42, 0.66


def noise_fog_material():
    """Principled Volume with Density = PEAK * clamp(map(noise(object coords)))."""
    mat = bpy.data.materials.new("Fog")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (600, 0)
    out.target = "ALL"
    coords = nt.nodes.new("ShaderNodeTexCoord")
    coords.location = (-800, 0)
    noise = nt.nodes.new("ShaderNodeTexNoise")
    noise.name = noise.label = "Fog Noise"
    noise.location = (-600, 0)
    noise.noise_dimensions = "3D"
    noise.noise_type = "FBM"
    noise.normalize = True
    noise.inputs["Scale"].default_value = 0.45
    noise.inputs["Detail"].default_value = 2.0
    noise.inputs["Roughness"].default_value = 0.55
    noise.inputs["Lacunarity"].default_value = 2.0
    noise.inputs["Distortion"].default_value = 0.0
    remap = nt.nodes.new("ShaderNodeMapRange")
    remap.name = remap.label = "Fog Patches"
    remap.location = (-350, 0)
    remap.data_type = "FLOAT"
    remap.interpolation_type = "SMOOTHSTEP"
    remap.clamp = True
    remap.inputs["From Min"].default_value = NOISE_CLEAR
    remap.inputs["From Max"].default_value = NOISE_THICK
    remap.inputs["To Min"].default_value = 0.0
    remap.inputs["To Max"].default_value = 1.0
    scale = nt.nodes.new("ShaderNodeMath")
    scale.name = scale.label = "Fog Peak Density"
    scale.location = (-150, 0)
    scale.operation = "MULTIPLY"
    scale.use_clamp = False
    scale.inputs[1].default_value = PEAK_DENSITY
    vol = kit.principled_volume_node(nt, "Medium", density=1.0, color=(0.9, 0.9, 0.9))
    vol.location = (100, 0)
    nt.links.new(coords.outputs["Object"], noise.inputs["Vector"])
    nt.links.new(noise.outputs["Factor"], remap.inputs["Value"])
    nt.links.new(remap.outputs["Result"], scale.inputs[0])
    nt.links.new(scale.outputs["Value"], vol.inputs["Density"])
    nt.links.new(vol.outputs["Volume"], out.inputs["Volume"])
    return mat


def build():
    scene = kit.new_scene(NAME, RESOLUTION, max_bounces=6, volume_bounces=0)
    build_room(scene)
    add_fog_box(noise_fog_material())
    return scene


if __name__ == "__main__":
    build()
    kit.save(Path(__file__).with_name(f"{NAME}.blend"))
