"""street: a camera moving down a foggy street at night (an animation, 24 frames at 24 fps).

Only the camera moves (keyframed location and a slight pan), so Cycles' persistent data can
keep the fog's volume octree from frame to frame. The camera dollies 5 m forward past four
street lamps (``Lamp.1`` ... in emissive bulbs), house fronts, a parked car and a sign, inside
a large fog box ``Fog``: a Principled Volume whose density is a Noise Texture in the box's own
coordinates over a thin constant floor, thinning with height.

Run: ``python street.py`` writes street.blend next to this file."""
from __future__ import annotations

from pathlib import Path

import bpy

import _scene_kit as kit

NAME = "street"
RESOLUTION = (256, 144)
FPS, FRAME_START, FRAME_END = 24, 1, 24

ROAD_WIDTH = 7.0                     # kerb to kerb; the road's centre line is x = 0
PAVEMENT_WIDTH, KERB_HEIGHT = 3.0, 0.15
STREET_START, STREET_END = -15.0, 90.0
FRONT_X = ROAD_WIDTH / 2 + PAVEMENT_WIDTH          # where the house fronts stand

#: The fog: extinction per metre = FLOOR + PEAK * patches(noise), times a height falloff
#: from 1 at the ground to HIGH at HIGH_Z metres. With the patches' mean near a third, a
#: lamp 40 m down the street keeps roughly exp(-2.5) of its light: far things fade.
FOG_FLOOR, FOG_PEAK = 0.004, 0.10
NOISE_CLEAR, NOISE_THICK = 0.45, 0.62
FOG_HIGH, FOG_HIGH_Z = 0.3, 12.0
#: The fog box: x, y, z extent (it rests on the ground: its base 10 cm below the road).
FOG_SIZE = (44.0, STREET_END - STREET_START, 16.0)

#: Camera keys (frame, location, target): a 5 m dolly up the right-hand lane, panning
#: slightly from the left pavement towards the right.
CAMERA_KEYS = ((FRAME_START, (-0.9, -4.0, 1.6), (-3.0, 40.0, 2.4)),
               (FRAME_END, (-0.7, 1.0, 1.6), (0.6, 40.0, 2.4)))

#: (number, x of the pole, y) of the street lamps; the arm reaches LAMP_ARM over the road.
LAMPS = ((1, 4.2, 9.0), (2, -4.2, 19.0), (3, 4.2, 31.0), (4, -4.2, 45.0))
LAMP_HEIGHT, LAMP_ARM = 5.2, 1.2
LAMP_COLOR = (1.0, 0.72, 0.42)       # sodium-ish warm white

#: House fronts (name, side, y start, y end, height, colour): boxes 8 m deep behind the
#: pavement, a gap on the left for the garden wall.
BUILDINGS = (("L.1", -1, -15.0, 4.0, 9.0, (0.30, 0.26, 0.22)),
             ("L.2", -1, 4.0, 16.0, 12.0, (0.22, 0.22, 0.24)),
             ("L.3", -1, 30.0, 52.0, 10.0, (0.34, 0.28, 0.24)),
             ("L.4", -1, 52.0, 90.0, 14.0, (0.25, 0.24, 0.23)),
             ("R.1", 1, -15.0, 12.0, 11.0, (0.27, 0.25, 0.24)),
             ("R.2", 1, 12.0, 26.0, 8.0, (0.36, 0.30, 0.25)),
             ("R.3", 1, 26.0, 48.0, 13.0, (0.23, 0.23, 0.25)),
             ("R.4", 1, 48.0, 90.0, 10.0, (0.30, 0.27, 0.24)))
#: The garden wall between L.2 and L.3 (y from, to; height).
WALL = (16.0, 30.0, 2.2)

CAR_X, CAR_Y = 2.35, 15.0            # parked against the right kerb, facing up the street
CAR_LENGTH, CAR_WIDTH = 4.2, 1.8
SIGN_X, SIGN_Y, SIGN_HEIGHT = 4.0, 24.0, 2.4


def add_ground():
    asphalt = kit.surface_material("Asphalt", (0.05, 0.05, 0.055), roughness=0.65)
    paving = kit.surface_material("Paving", (0.16, 0.15, 0.14), roughness=0.8)
    kerb = kit.surface_material("Kerb", (0.30, 0.30, 0.29), roughness=0.7)
    paint = kit.surface_material("Road Paint", (0.7, 0.7, 0.68), roughness=0.5)
    length = STREET_END - STREET_START
    mid_y = (STREET_START + STREET_END) / 2
    kit.mesh_object("Road", kit.plane(ROAD_WIDTH, length, center=(0.0, mid_y, 0.0)), asphalt)

    def dashes(bm):
        y = STREET_START
        while y < STREET_END:
            kit.box(bm, (0.12, 2.5, 0.004), (0.0, y + 1.25, 0.002))
            y += 7.5
    kit.mesh_object("Road Markings", dashes, paint)
    for side, sign in (("L", -1.0), ("R", 1.0)):
        inner = ROAD_WIDTH / 2
        kit.mesh_object(f"Pavement.{side}", lambda bm, s=sign, i=inner: kit.box(
            bm, (PAVEMENT_WIDTH - 0.2, length, KERB_HEIGHT),
            (s * (i + 0.2 + (PAVEMENT_WIDTH - 0.2) / 2), mid_y, KERB_HEIGHT / 2)), paving)
        kit.mesh_object(f"Kerb.{side}", lambda bm, s=sign, i=inner: kit.box(
            bm, (0.2, length, KERB_HEIGHT + 0.01), (s * (i + 0.1), mid_y, (KERB_HEIGHT + 0.01) / 2)),
            kerb)


def add_buildings():
    for name, side, y0, y1, height, colour in BUILDINGS:
        depth = 8.0
        x = side * (FRONT_X + depth / 2)
        kit.mesh_object(f"Building.{name}", lambda bm, x=x, y0=y0, y1=y1, h=height: kit.box(
            bm, (depth, y1 - y0, h), (x, (y0 + y1) / 2, h / 2)),
            kit.surface_material(f"Building {name}", colour, roughness=0.85))
    y0, y1, height = WALL
    kit.mesh_object("Wall", lambda bm: kit.box(bm, (0.4, y1 - y0, height),
                                               (-(FRONT_X - 0.2), (y0 + y1) / 2, height / 2)),
                    kit.surface_material("Wall", (0.2, 0.1, 0.07), roughness=0.9))


def add_car():
    """Body, cabin and wheels, all boxes; parked against the right kerb."""
    paint = kit.surface_material("Car Paint", (0.05, 0.12, 0.30), roughness=0.3, coat=1.0)
    glass = kit.surface_material("Car Glass", (0.02, 0.02, 0.025), roughness=0.05)
    tyre = kit.surface_material("Tyre", (0.02, 0.02, 0.02), roughness=0.8)
    at = (CAR_X, CAR_Y, 0.0)
    kit.mesh_object("Car", lambda bm: kit.box(bm, (CAR_WIDTH, CAR_LENGTH, 0.7), (0.0, 0.0, 0.65)),
                    paint, location=at)
    kit.mesh_object("Car.Cabin", lambda bm: kit.box(bm, (1.6, 2.1, 0.55), (0.0, -0.2, 1.275)),
                    glass, location=at)

    def wheels(bm):
        for x in (-0.82, 0.82):
            for y in (-1.3, 1.3):
                kit.box(bm, (0.24, 0.64, 0.64), (x, y, 0.32))
    kit.mesh_object("Car.Wheels", wheels, tyre, location=at)


def add_lamps():
    kit.add_street_lamps(LAMPS, LAMP_HEIGHT, LAMP_ARM, LAMP_COLOR, energy=500.0)


def add_sign():
    """A blue parking sign with a white rim on the right pavement, facing the camera."""
    grey = kit.surface_material("Sign Pole", (0.35, 0.35, 0.36), roughness=0.4, metallic=1.0)
    kit.mesh_object("Sign.Pole", kit.cylinder(0.04, SIGN_HEIGHT, segments=10,
                                              center=(SIGN_X, SIGN_Y + 0.04, SIGN_HEIGHT / 2)), grey)
    kit.mesh_object("Sign", lambda bm: kit.box(bm, (0.6, 0.02, 0.6), (SIGN_X, SIGN_Y - 0.01, SIGN_HEIGHT)),
                    kit.surface_material("Sign", (0.02, 0.15, 0.6), roughness=0.3))
    kit.mesh_object("Sign.Rim", lambda bm: kit.box(bm, (0.68, 0.02, 0.68), (SIGN_X, SIGN_Y, SIGN_HEIGHT)),
                    kit.surface_material("Sign Rim", (0.85, 0.85, 0.85), roughness=0.3))


def noise_fog_material():
    """Principled Volume, Density = (FLOOR + PEAK * patches(noise)) * falloff(height), all in
    the fog box's Object coordinates (metres; z = 0 at the box's base)."""
    mat = bpy.data.materials.new("Fog")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (800, 0)
    out.target = "ALL"
    coords = nt.nodes.new("ShaderNodeTexCoord")
    coords.location = (-1000, 0)
    noise = nt.nodes.new("ShaderNodeTexNoise")
    noise.name = noise.label = "Fog Noise"
    noise.location = (-800, 100)
    noise.noise_dimensions = "3D"
    noise.noise_type = "FBM"
    noise.normalize = True
    noise.inputs["Scale"].default_value = 0.25
    noise.inputs["Detail"].default_value = 3.0
    noise.inputs["Roughness"].default_value = 0.55
    noise.inputs["Lacunarity"].default_value = 2.0
    noise.inputs["Distortion"].default_value = 0.0
    patches = nt.nodes.new("ShaderNodeMapRange")
    patches.name = patches.label = "Fog Patches"
    patches.location = (-550, 100)
    patches.data_type = "FLOAT"
    patches.interpolation_type = "SMOOTHSTEP"
    patches.clamp = True
    patches.inputs["From Min"].default_value = NOISE_CLEAR
    patches.inputs["From Max"].default_value = NOISE_THICK
    patches.inputs["To Min"].default_value = FOG_FLOOR
    patches.inputs["To Max"].default_value = FOG_FLOOR + FOG_PEAK
    height = nt.nodes.new("ShaderNodeSeparateXYZ")
    height.location = (-800, -150)
    falloff = nt.nodes.new("ShaderNodeMapRange")
    falloff.name = falloff.label = "Fog Height Falloff"
    falloff.location = (-550, -150)
    falloff.data_type = "FLOAT"
    falloff.interpolation_type = "LINEAR"
    falloff.clamp = True
    falloff.inputs["From Min"].default_value = 0.0
    falloff.inputs["From Max"].default_value = FOG_HIGH_Z
    falloff.inputs["To Min"].default_value = 1.0
    falloff.inputs["To Max"].default_value = FOG_HIGH
    density = nt.nodes.new("ShaderNodeMath")
    density.name = density.label = "Fog Density"
    density.location = (-300, 0)
    density.operation = "MULTIPLY"
    density.use_clamp = False
    vol = kit.principled_volume_node(nt, "Medium", density=1.0, color=(0.9, 0.9, 0.9),
                                     anisotropy=0.3)
    vol.location = (300, 0)
    nt.links.new(coords.outputs["Object"], noise.inputs["Vector"])
    nt.links.new(coords.outputs["Object"], height.inputs["Vector"])
    nt.links.new(noise.outputs["Factor"], patches.inputs["Value"])
    nt.links.new(height.outputs["Z"], falloff.inputs["Value"])
    nt.links.new(patches.outputs["Result"], density.inputs[0])
    nt.links.new(falloff.outputs["Result"], density.inputs[1])
    nt.links.new(density.outputs["Value"], vol.inputs["Density"])
    nt.links.new(vol.outputs["Volume"], out.inputs["Volume"])
    return mat


def add_fog_box():
    """The medium: a box around the whole street, its origin on the ground under the middle
    of the street, its base 10 cm below the road (no face coincides with the ground)."""
    sx, sy, sz = FOG_SIZE
    return kit.mesh_object("Fog", lambda bm: kit.box(bm, (sx, sy, sz), (0.0, 0.0, sz / 2 - 0.1)),
                           noise_fog_material(),
                           location=(0.0, (STREET_START + STREET_END) / 2, 0.0))


def add_camera():
    """The camera and its two keys (linear: a steady dolly and pan, no easing)."""
    frame, location, target = CAMERA_KEYS[0]
    cam = kit.add_camera("Camera", location=location, target=target, lens=32.0, clip_end=300.0)
    for frame, location, target in CAMERA_KEYS:
        cam.location = location
        cam.rotation_euler = kit.look_at_rotation(location, target)
        cam.keyframe_insert("location", frame=frame)
        cam.keyframe_insert("rotation_euler", frame=frame)
    from bpy_extras.anim_utils import action_get_channelbag_for_slot

    channels = action_get_channelbag_for_slot(cam.animation_data.action, cam.animation_data.action_slot)
    for curve in channels.fcurves:
        for key in curve.keyframe_points:
            key.interpolation = "LINEAR"
    return cam


def build():
    scene = kit.new_scene(NAME, RESOLUTION, max_bounces=4, volume_bounces=0)
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    scene.frame_start, scene.frame_end = FRAME_START, FRAME_END
    # Dusk over the town: a dim blue sky, which also lights the fog a little.
    kit.set_world(scene, color=(0.010, 0.014, 0.028), strength=1.0)
    add_ground()
    add_buildings()
    add_car()
    add_lamps()
    add_sign()
    add_fog_box()
    add_camera()
    scene.frame_set(FRAME_START)
    return scene


if __name__ == "__main__":
    build()
    kit.save(Path(__file__).with_name(f"{NAME}.blend"))
