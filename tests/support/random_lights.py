"""Lights for a random scene (``random_scenes``), as artists light fog: a lamp hanging in
it, a spot aimed into it, an area light beside it, a sun from above; one to three of them.

The X-map suite needs no light, so its scenes stay as they are; the volume-sampling suite
(``test_scatter_random.py``) lights them from a generator of its own seed.
"""
from __future__ import annotations

import math

import numpy as np

from support.random_scenes import X_RANGE, Y_FAR, Y_NEAR

KINDS = ("POINT", "POINT", "SPOT", "AREA", "SUN")


def add_random_lights(bpy, scene, seed: int) -> list[str]:
    """Link one to three lights drawn from ``seed`` into ``scene``; what was added, in words."""
    rng = np.random.default_rng(10_000 + seed)
    added = []
    for index in range(int(rng.integers(1, 4))):
        kind = KINDS[int(rng.integers(len(KINDS)))]
        light = bpy.data.lights.new(f"{kind.title()}.{index}", kind)
        obj = bpy.data.objects.new(light.name, light)
        scene.collection.objects.link(obj)
        x, y = rng.uniform(-X_RANGE, X_RANGE), rng.uniform(Y_NEAR, Y_FAR)
        if kind == "SUN":
            light.energy = float(rng.uniform(1.0, 5.0))
            obj.rotation_euler = (float(rng.uniform(0.0, 1.0)), float(rng.uniform(-0.5, 0.5)), 0.0)
            added.append(f"sun {light.energy:.1f}")
            continue
        obj.location = (x, y, float(rng.uniform(0.5, 6.0)))
        light.energy = float(rng.uniform(100.0, 3000.0))
        if kind == "SPOT":
            light.spot_size = math.radians(float(rng.uniform(30.0, 100.0)))
            target = np.array([rng.uniform(-2, 2), rng.uniform(6, 10), 0.0]) - np.array(obj.location)
            # A spot shines along its local -Z, as a camera looks: the camera's angles.
            obj.rotation_euler = (math.atan2(math.hypot(target[0], target[1]), -target[2]), 0.0,
                                  math.atan2(-target[0], target[1]))
        elif kind == "AREA":
            light.size = float(rng.uniform(0.5, 2.0))
        light.shadow_soft_size = float(rng.uniform(0.05, 0.5))
        added.append(f"{kind.lower()} {light.energy:.0f} W at ({x:.1f}, {y:.1f}, {obj.location.z:.1f})")
    return added
