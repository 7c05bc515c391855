"""road: the paper's foggy road at night.

Tests visible light sources in a world-volume fog (the L map): the sky is an empty, nearly
black world background and the whole world is filled with a homogeneous Principled Volume
(``World`` medium, node ``Fog``). An oncoming car faces the camera with two headlights,
each a spot light aimed at the camera (``Headlight.L``, ``Headlight.R``; left and right
as the car sees them) in front of a small emissive lens disc (``Headlight.L.Lens``, ...).
Street lamps (point lights ``Lamp.1`` ... with emissive bulbs ``Lamp.1.Bulb`` ...) line the
road; two traffic signs (``Sign.Stop``, ``Sign.Warning``) each stand a few metres behind
a lamp, in its light: the salient features the paper's viewers looked at.

Run: ``python road.py`` writes road.blend next to this file.
"""
from __future__ import annotations

import math
from pathlib import Path

import bpy  # noqa: F401  (first: the bpy module makes bmesh and mathutils importable)
import bmesh
from mathutils import Matrix

import _scene_kit as kit

NAME = "road"
RESOLUTION = (512, 288)

#: Extinction of the fog per metre: a lamp 50 m away keeps exp(-1.5), a fifth, of its light.
FOG_DENSITY = 0.03

ROAD_WIDTH, ROAD_START, ROAD_END = 7.5, -10.0, 160.0
CAR_X, CAR_Y = -1.8, 26.0            # the car drives in the left lane towards the camera
CAR_LENGTH, CAR_WIDTH = 4.4, 1.8
HEADLIGHT_Z, HEADLIGHT_HALF_SPAN = 0.72, 0.62

#: (number, x of the pole, y) of the street lamps; the arm reaches 1.4 m over the road.
LAMPS = ((1, -4.6, 12.0), (2, 4.6, 18.0), (3, -4.6, 34.0), (4, 4.6, 46.0), (5, -4.6, 62.0),
         (6, 4.6, 78.0))
LAMP_HEIGHT, LAMP_ARM = 5.5, 1.4


def road_markings(bm):
    """Dashed centre line (3 m dashes every 9 m) and solid edge lines, 15 cm wide."""
    def strip(x, y0, y1, width=0.15):
        m = Matrix.Translation((x, (y0 + y1) / 2, 0.005)) @ Matrix.Diagonal(
            (width / 2, (y1 - y0) / 2, 1.0, 1.0))
        bmesh.ops.create_grid(bm, x_segments=1, y_segments=1, size=1.0, matrix=m)
    y = ROAD_START
    while y < ROAD_END:
        strip(0.0, y, y + 3.0)
        y += 9.0
    for side in (-1.0, 1.0):
        strip(side * (ROAD_WIDTH / 2 - 0.25), ROAD_START, ROAD_END)


def add_ground():
    asphalt = kit.surface_material("Asphalt", (0.045, 0.045, 0.05), roughness=0.55)
    verge = kit.surface_material("Verge", (0.025, 0.035, 0.02), roughness=0.9)
    paint = kit.surface_material("Road Paint", (0.75, 0.75, 0.72), roughness=0.5)
    length = ROAD_END - ROAD_START
    kit.mesh_object("Road", kit.plane(ROAD_WIDTH, length, center=(0.0, (ROAD_START + ROAD_END) / 2, 0.0)),
                    asphalt)
    kit.mesh_object("Road Markings", road_markings, paint)
    kit.mesh_object("Verge", kit.plane(120.0, length, center=(0.0, (ROAD_START + ROAD_END) / 2, -0.03)),
                    verge)


def add_car():
    """Body, cabin and wheels as boxes and cylinders; the front faces -Y (the camera)."""
    paint = kit.surface_material("Car Paint", (0.35, 0.02, 0.03), roughness=0.25, coat=1.0)
    glass = kit.surface_material("Car Glass", (0.02, 0.02, 0.025), roughness=0.05)
    tyre = kit.surface_material("Tyre", (0.02, 0.02, 0.02), roughness=0.8)
    front = CAR_Y - CAR_LENGTH / 2

    def body(bm):
        kit.box(bm, (CAR_WIDTH, CAR_LENGTH, 0.75), (0.0, 0.0, 0.7))
    kit.mesh_object("Car", body, paint, location=(CAR_X, CAR_Y, 0.0))
    kit.mesh_object("Car.Cabin", lambda bm: kit.box(bm, (1.6, 2.2, 0.55), (0.0, 0.35, 1.345)), glass,
                    location=(CAR_X, CAR_Y, 0.0))

    def wheels(bm):
        for x in (-0.8, 0.8):
            for y in (-1.35, 1.35):
                bmesh.ops.create_cone(bm, cap_ends=True, segments=20, radius1=0.34, radius2=0.34,
                                      depth=0.24, matrix=Matrix.Translation((x, y, 0.34))
                                      @ Matrix.Rotation(math.pi / 2, 4, "Y"))
    kit.mesh_object("Car.Wheels", wheels, tyre, location=(CAR_X, CAR_Y, 0.0))

    lens = kit.emission_material("Headlight Lens", (1.0, 0.95, 0.85), strength=100.0)
    # The car faces -Y, so its own left is +X.
    for side, sign in (("L", 1.0), ("R", -1.0)):
        x = CAR_X + sign * HEADLIGHT_HALF_SPAN
        # The lens disc faces -Y (a +90 degree turn about X takes +Z to -Y), just in front of
        # the body; the spot sits 3 cm ahead of the lens.
        kit.seen_by_camera_only(kit.mesh_object(
            f"Headlight.{side}.Lens", kit.disc(0.13, segments=24), lens,
            location=(x, front - 0.01, HEADLIGHT_Z), rotation=kit.degrees(90.0, 0.0, 0.0)))
        kit.add_light(f"Headlight.{side}", "SPOT", location=(x, front - 0.04, HEADLIGHT_Z),
                      target=(x + 0.6 * sign, front - 30.0, 0.4), energy=1200.0,
                      color=(1.0, 0.95, 0.85), radius=0.08,
                      spot_size=kit.degrees(50.0)[0], spot_blend=0.5)


def add_lamps():
    kit.add_street_lamps(LAMPS, LAMP_HEIGHT, LAMP_ARM, (1.0, 0.78, 0.5), energy=700.0)


#: (name, pole x, y, panel centre height, sides, panel radius, turn, colour, rim colour):
#: a red octagonal stop sign with a white rim, a yellow diamond with a black rim.
SIGNS = (("Stop", 4.0, 22.0, 2.3, 8, 0.45, math.pi / 8, (0.85, 0.01, 0.01), (0.9, 0.9, 0.9)),
         ("Warning", -4.0, 16.0, 2.4, 4, 0.5, 0.0, (0.95, 0.65, 0.0), (0.01, 0.01, 0.01)))


def add_signs():
    """Flat sign panels facing the camera, each on a larger rim panel just behind it."""
    grey = kit.surface_material("Sign Pole", (0.35, 0.35, 0.36), roughness=0.4, metallic=1.0)
    face = kit.degrees(90.0, 0.0, 0.0)          # +Z of the panel -> -Y, towards the camera

    def polygon(radius, sides, turn, behind=0.0):
        m = Matrix.Translation((0.0, 0.0, -behind)) @ Matrix.Rotation(turn, 4, "Z")
        return lambda bm: bmesh.ops.create_circle(bm, cap_ends=True, segments=sides, radius=radius,
                                                  matrix=m)

    for name, x, y, height, sides, radius, turn, colour, rim in SIGNS:
        kit.mesh_object(f"Sign.{name}.Pole", kit.cylinder(0.04, height, segments=10,
                                                          center=(x, y + 0.04, height / 2)), grey)
        kit.mesh_object(f"Sign.{name}", polygon(radius, sides, turn),
                        kit.surface_material(f"Sign {name}", colour, roughness=0.3),
                        location=(x, y, height), rotation=face)
        kit.mesh_object(f"Sign.{name}.Rim", polygon(radius * 1.1, sides, turn, behind=0.01),
                        kit.surface_material(f"Sign {name} Rim", rim, roughness=0.3),
                        location=(x, y, height), rotation=face)


def build():
    scene = kit.new_scene(NAME, RESOLUTION, max_bounces=4, volume_bounces=0)
    kit.set_world(scene, color=(0.002, 0.0025, 0.004), strength=1.0,
                  fog=dict(density=FOG_DENSITY, color=(0.9, 0.9, 0.9), anisotropy=0.2))
    add_ground()
    add_car()
    add_lamps()
    add_signs()
    kit.add_camera("Camera", location=(1.7, -2.0, 1.4), target=(0.2, 40.0, 1.6), lens=30.0,
                   clip_end=500.0)
    return scene


if __name__ == "__main__":
    build()
    kit.save(Path(__file__).with_name(f"{NAME}.blend"))
