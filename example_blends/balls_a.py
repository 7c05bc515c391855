"""balls A: coloured spheres on a floor in thin homogeneous fog.

Tests the homogeneous case of the X map: the fog is a box mesh ``Fog`` whose material is
a Principled Volume with a constant density, so the extinction is one number and the
transmittance to a surface is exp(-kappa s). One area light ``Key`` lights the room from
above; it is out of frame (this scene has no visible light sources).

Run: ``python balls_a.py`` writes balls_a.blend next to this file.
"""
from __future__ import annotations

from pathlib import Path

import _scene_kit as kit

NAME = "balls_a"
RESOLUTION = (512, 384)

#: Extinction of the thin fog per metre: about 40 % of the light from the back wall
#: (11 m from the camera) gets through.
FOG_DENSITY = 0.04

#: (name, radius, (x, y), material settings) of the spheres, left to right, front to back.
BALLS = (
    ("Ball.Red", 0.55, (-2.3, 0.2), dict(color=(0.80, 0.06, 0.05), roughness=0.45)),
    ("Ball.Gold", 0.70, (-0.9, 1.6), dict(color=(1.00, 0.71, 0.29), roughness=0.2, metallic=1.0)),
    ("Ball.Glass", 0.50, (0.2, -0.4), dict(color=(1.0, 1.0, 1.0), roughness=0.0, transmission=1.0,
                                           ior=1.5)),
    ("Ball.Blue", 0.80, (1.6, 1.2), dict(color=(0.05, 0.15, 0.80), roughness=0.15, coat=1.0)),
    ("Ball.Green", 0.45, (2.7, -0.2), dict(color=(0.08, 0.60, 0.10), roughness=0.6)),
    ("Ball.White", 0.60, (-0.1, 3.3), dict(color=(0.85, 0.85, 0.82), roughness=0.35)),
)


def build_room(scene):
    """Floor, back wall, the spheres, the key light and the camera: what both balls
    scenes share. The fog box is left to the caller."""
    kit.set_world(scene, color=(0.03, 0.035, 0.045), strength=1.0)
    floor = kit.surface_material("Floor", (0.45, 0.42, 0.38), roughness=0.8)
    wall = kit.surface_material("Wall", (0.55, 0.55, 0.58), roughness=0.9)
    kit.mesh_object("Floor", kit.plane(16.0, 14.0, center=(0.0, 1.0, 0.0)), floor)
    kit.mesh_object("Wall", kit.plane(16.0, 8.0), wall, location=(0.0, 5.0, 4.0),
                    rotation=kit.degrees(90.0, 0.0, 0.0))
    for name, radius, (x, y), settings in BALLS:
        kit.mesh_object(name, kit.uv_sphere(radius), kit.surface_material(name, **settings),
                        location=(x, y, radius), smooth=True)
    kit.add_light("Key", "AREA", location=(-3.0, -2.0, 6.0), target=(0.0, 1.0, 0.0),
                  energy=1100.0, color=(1.0, 0.95, 0.88), size=2.5)
    kit.add_camera("Camera", location=(0.0, -7.0, 2.6), target=(0.0, 1.2, 0.5), lens=32.0,
                   clip_end=100.0)


def add_fog_box(material):
    """The medium: a box around everything in frame; the camera stays outside it."""
    return kit.mesh_object("Fog", lambda bm: kit.box(bm, (14.0, 10.5, 7.0), (0.0, 0.0, 0.0)),
                           material, location=(0.0, 0.2, 3.4))


def build():
    scene = kit.new_scene(NAME, RESOLUTION, max_bounces=6, volume_bounces=0)
    build_room(scene)
    add_fog_box(kit.volume_material("Fog", density=FOG_DENSITY, color=(0.9, 0.9, 0.9)))
    return scene


if __name__ == "__main__":
    build()
    kit.save(Path(__file__).with_name(f"{NAME}.blend"))
