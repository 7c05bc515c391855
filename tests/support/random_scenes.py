"""A seeded generator of small scenes with participating media, for the randomized X-map oracle
suite (``test_xmap_random.py``, ``bench/bench_xmap_oracle.py``): X compared with what Cycles
renders.

From ``numpy.random.default_rng(seed)``: a perspective or orthographic camera outside, inside
or on the face of a volume; a ground plane and a few surfaces; object volumes (boxes resting on
the ground, spheres, cylinders, cones, tori; nested, stacked or sharing a face) with any volume
shader, their density constant, noise or gradient; sometimes a world volume and an OpenVDB
smoke grid. Optical depths across a volume of about 0.2 to 2, so no map is empty or black."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from support.xmap_scenes import base_scene, smoke_volume_object

WIDTH, HEIGHT = 64, 36
#: Where the scene's things stand: x in [-X, X], y in [Y0, Y1] (the camera looks along +y).
X_RANGE, Y_NEAR, Y_FAR = 5.0, 3.0, 14.0
SURFACE_SHAPES = ("cube", "uv_sphere", "ico_sphere", "cylinder", "cone", "torus")
VOLUME_SHAPES = ("cube", "cube", "cube", "uv_sphere", "cylinder", "cone", "torus")
CLOSURES = ("ShaderNodeVolumePrincipled", "ShaderNodeVolumeScatter",
            "ShaderNodeVolumeAbsorption", "ShaderNodeVolumeCoefficients")
CAMERA_PLACES = ("outside", "inside", "on a boundary", "clip start inside")


@dataclass
class RandomScene:
    """What was built for one seed."""

    seed: int
    scene: object
    features: list[str] = field(default_factory=list)

    def describe(self) -> str:
        return f"seed {self.seed}: " + ", ".join(self.features)


def build_random_scene(bpy, seed: int, width: int = WIDTH, height: int = HEIGHT) -> RandomScene:
    """Replace the session's scene with the one ``seed`` draws (see the module notes)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.engine = "CYCLES"
    bpy.context.scene.cycles.device = "CPU"
    rng = np.random.default_rng(seed)
    builder = _Builder(bpy, rng, seed, width, height)
    return builder.build()


class _Builder:
    def __init__(self, bpy, rng, seed, width, height):
        self.bpy, self.rng = bpy, rng
        self.out = RandomScene(seed=seed, scene=None)
        self.width, self.height = width, height
        self.boxes: list = []          # volume boxes (object, centre, half sizes), axis-aligned

    # --- helpers --------------------------------------------------------------------
    def feature(self, text: str) -> None:
        if text not in self.out.features:
            self.out.features.append(text)

    def uniform(self, lo, hi):
        return float(self.rng.uniform(lo, hi))

    def chance(self, p) -> bool:
        return bool(self.rng.random() < p)

    def primitive(self, shape: str, location, material=None, **kwargs):
        ops = self.bpy.ops.mesh
        if shape == "cube":
            ops.primitive_cube_add(size=2.0, location=location)
        elif shape == "uv_sphere":
            ops.primitive_uv_sphere_add(radius=1.0, segments=24, ring_count=12, location=location)
        elif shape == "ico_sphere":
            ops.primitive_ico_sphere_add(radius=1.0, subdivisions=2, location=location)
        elif shape == "cylinder":
            ops.primitive_cylinder_add(radius=1.0, depth=2.0, vertices=20, location=location)
        elif shape == "cone":
            ops.primitive_cone_add(radius1=1.0, depth=2.0, vertices=20, location=location)
        elif shape == "torus":
            ops.primitive_torus_add(major_radius=1.0, minor_radius=0.35, major_segments=24,
                                    minor_segments=10, location=location)
        ob = self.bpy.context.active_object
        if material is not None:
            ob.data.materials.append(material)
        return ob

    def spot(self, margin=0.0):
        return (self.uniform(-X_RANGE + margin, X_RANGE - margin),
                self.uniform(Y_NEAR + margin, Y_FAR - margin))

    # --- the scene ------------------------------------------------------------------
    def build(self) -> RandomScene:
        bpy, rng = self.bpy, self.rng
        self.camera_place = CAMERA_PLACES[int(rng.integers(len(CAMERA_PLACES)))]
        ortho = self.chance(0.25)
        eye = self.camera_eye(ortho)
        scene = base_scene(bpy, self.width, self.height, location=eye,
                           rotation=self.camera_rotation(eye, ortho))
        self.out.scene = scene
        self.camera_settings(scene.camera.data, ortho)
        self.ground()
        for _ in range(int(rng.integers(1, 4))):
            self.surface()
        self.volumes(scene, eye)
        if self.chance(0.35):
            self.world_volume(scene)
        if self.chance(0.15):
            self.smoke(scene)
        bpy.context.view_layer.update()
        self.feature(f"{self.width}x{self.height}")
        return self.out

    def camera_eye(self, ortho: bool):
        if ortho:
            return (self.uniform(-4, 4), self.uniform(-14, -9), self.uniform(4, 10))
        return (self.uniform(-2, 2), self.uniform(-2.5, 0.5), self.uniform(0.8, 3.5))

    def camera_rotation(self, eye, ortho: bool):
        """Euler angles (degrees) looking from ``eye`` at a point in the scene's middle."""
        target = np.array([self.uniform(-2, 2), self.uniform(7, 10), self.uniform(0.0, 1.5)])
        direction = target - np.asarray(eye)
        pitch = math.degrees(math.atan2(math.hypot(direction[0], direction[1]), -direction[2]))
        yaw = math.degrees(math.atan2(-direction[0], direction[1]))
        return (pitch, self.uniform(-4, 4), yaw)

    def camera_settings(self, camera, ortho: bool):
        if ortho:
            camera.type = "ORTHO"
            camera.ortho_scale = self.uniform(8, 16)
            self.feature("orthographic")
        else:
            camera.lens = self.uniform(18, 45)
            self.feature("perspective")
        # A clip end near the scene, as small scenes have: rays that pass everything
        # (through a floor, at a tie) end there instead of marching a world volume for
        # a kilometre in every Cycles render.
        camera.clip_end = self.uniform(60, 150)
        if self.chance(0.4):
            camera.shift_x, camera.shift_y = self.uniform(-0.2, 0.2), self.uniform(-0.15, 0.15)
            self.feature("lens shift")

    def ground(self):
        bpy = self.bpy
        size = self.uniform(30, 60)
        if self.chance(0.3):
            bpy.ops.mesh.primitive_grid_add(x_subdivisions=12, y_subdivisions=12, size=size,
                                            location=(0.0, 8.0, 0.0))
            self.feature("subdivided ground")
        else:
            bpy.ops.mesh.primitive_plane_add(size=size, location=(0.0, 8.0, 0.0))

    def surface(self):
        shape = SURFACE_SHAPES[int(self.rng.integers(len(SURFACE_SHAPES)))]
        x, y = self.spot(margin=1.0)
        scale = np.array([self.uniform(0.4, 1.2) for _ in range(3)])
        resting = self.chance(0.5)
        ob = self.primitive(shape, (x, y, 0.0))
        ob.scale = scale
        if self.chance(0.2):
            ob.scale = (-scale[0], scale[1], scale[2])
            self.feature("mirrored surface")
        if resting and shape != "torus":
            ob.rotation_euler = (0.0, 0.0, self.uniform(0, math.pi))
            ob.location.z = scale[2]                # its bottom on the ground
            self.feature("surface resting on the ground")
        else:
            ob.rotation_euler = tuple(self.uniform(-0.6, 0.6) for _ in range(3))
            ob.location.z = self.uniform(1.0, 3.0)

    # --- volumes --------------------------------------------------------------------
    def volumes(self, scene, eye):
        place = self.camera_place
        if place == "inside":
            self.box_around_camera(eye)
        elif place == "on a boundary":
            self.box_through_eye(eye)
        elif place == "clip start inside":
            self.box_before_camera(scene, eye)
        else:
            self.feature("camera outside the volumes")
        for _ in range(int(self.rng.integers(0 if place != "outside" else 1, 3))):
            self.loose_volume()

    def material(self, heterogeneous=None):
        """A volume material of a random closure, its density constant, noise- or
        gradient-driven (``heterogeneous`` forces one or the other)."""
        bpy, rng = self.bpy, self.rng
        kind = CLOSURES[int(rng.integers(len(CLOSURES)))]
        material = bpy.data.materials.new(kind.replace("ShaderNode", ""))
        tree = material.node_tree
        tree.nodes.clear()
        output = tree.nodes.new("ShaderNodeOutputMaterial")
        node = tree.nodes.new(kind)
        extinction = self.uniform(0.05, 0.35)         # per unit, before the colour
        colour = tuple(self.uniform(0.2, 0.95) for _ in range(3)) + (1.0,)
        if kind == "ShaderNodeVolumeCoefficients":
            node.inputs["Absorption Coefficients"].default_value = tuple(
                extinction * self.uniform(0.2, 1.0) for _ in range(3))
            node.inputs["Scatter Coefficients"].default_value = tuple(
                extinction * self.uniform(0.0, 0.8) for _ in range(3))
            self.feature("Volume Coefficients")
        else:
            node.inputs["Color"].default_value = colour
            if kind == "ShaderNodeVolumeAbsorption":
                node.inputs["Color"].default_value = tuple(1 - c for c in colour[:3]) + (1.0,)
            if kind == "ShaderNodeVolumePrincipled":
                node.inputs["Absorption Color"].default_value = tuple(
                    self.uniform(0.0, 0.6) for _ in range(3)) + (1.0,)
            node.inputs["Density"].default_value = extinction / 0.6
            self.feature(kind.replace("ShaderNodeVolume", "") + " volume")
            if heterogeneous is None:
                heterogeneous = self.chance(0.45)
            if heterogeneous:
                self.drive_density(tree, node, extinction / 0.6)
        tree.links.new(node.outputs[0], output.inputs["Volume"])
        return material

    def drive_density(self, tree, node, scale):
        new, link = tree.nodes.new, tree.links.new
        coords = new("ShaderNodeTexCoord")
        factor = new("ShaderNodeMath")
        factor.operation = "MULTIPLY"
        factor.inputs[1].default_value = 2.0 * scale
        if self.chance(0.6):
            noise = new("ShaderNodeTexNoise")
            noise.inputs["Scale"].default_value = self.uniform(0.4, 2.0)
            noise.inputs["Detail"].default_value = self.uniform(0.0, 4.0)
            link(coords.outputs["Object"], noise.inputs["Vector"])
            ramp = new("ShaderNodeMapRange")
            ramp.inputs["From Min"].default_value = 0.3
            ramp.inputs["From Max"].default_value = 0.7
            link(noise.outputs["Fac"], ramp.inputs["Value"])
            link(ramp.outputs["Result"], factor.inputs[0])
            self.feature("noise-driven density")
        else:
            gradient = new("ShaderNodeTexGradient")
            gradient.gradient_type = ("LINEAR", "QUADRATIC", "SPHERICAL")[int(self.rng.integers(3))]
            source = "Generated" if self.chance(0.5) else "Object"
            link(coords.outputs[source], gradient.inputs["Vector"])
            link(gradient.outputs["Fac"], factor.inputs[0])
            self.feature(f"gradient-driven density ({source.lower()} coordinates)")
        link(factor.outputs[0], node.inputs["Density"])

    def add_box(self, centre, half, material, label, rotation_z=0.0):
        ob = self.primitive("cube", tuple(centre), material)
        ob.scale = tuple(half)
        ob.rotation_euler = (0.0, 0.0, rotation_z)
        if rotation_z == 0.0:
            self.boxes.append((ob, np.asarray(centre, float), np.asarray(half, float)))
        self.feature(label)
        return ob

    def box_around_camera(self, eye):
        """A fog box the camera stands in, most often resting on the ground (the issue's
        scene), the rest of the scene partly inside it."""
        half = np.array([self.uniform(3, 8), self.uniform(5, 9), self.uniform(2, 5)])
        centre = np.array([eye[0] + self.uniform(-1, 1), eye[1] + half[1] - self.uniform(1, 3),
                           half[2] if self.chance(0.6) else self.uniform(eye[2] - 0.5, eye[2] + 0.5)])
        centre[2] = max(centre[2], eye[2] - half[2] + 0.3)
        resting = centre[2] == half[2]
        self.add_box(centre, half, self.material(), "camera inside a volume")
        if resting:
            self.feature("volume box resting on the ground")
        if self.chance(0.4):                           # something nested in it
            x, y = self.spot(margin=2.0)
            ob = self.primitive("uv_sphere", (x, y, self.uniform(1.0, 2.0)), self.material(False))
            ob.scale = (self.uniform(0.6, 1.4),) * 3
            self.feature("nested volumes")

    def box_through_eye(self, eye):
        """A box with one face exactly through the eye: its top (eye at its height) or its
        near side (eye on the plane y = eye y), the box on the far side."""
        half = np.array([self.uniform(2, 6), self.uniform(3, 6), self.uniform(1, 2.5)])
        if self.chance(0.5):
            centre = np.array([eye[0], eye[1] + half[1] - 1.0, eye[2] - half[2]])
        else:
            centre = np.array([eye[0] + self.uniform(-1, 1), eye[1] + half[1], eye[2]])
        self.add_box(centre, half, self.material(), "camera on a volume's face")

    def box_before_camera(self, scene, eye):
        """A box in front of the camera whose near face lies inside the clip start."""
        half = np.array([self.uniform(2, 5), self.uniform(2, 4), self.uniform(1.5, 3)])
        gap = self.uniform(0.5, 2.0)
        centre = np.array([eye[0], eye[1] + gap + half[1], max(eye[2], half[2] + 0.2)])
        self.add_box(centre, half, self.material(), "clip start inside a volume")
        scene.camera.data.clip_start = gap + self.uniform(0.5, 1.5)

    def loose_volume(self):
        """A volume somewhere in the scene: resting, floating, stacked on or beside another
        box, or a second copy of a box."""
        shape = VOLUME_SHAPES[int(self.rng.integers(len(VOLUME_SHAPES)))]
        if shape == "cube" and self.boxes and self.chance(0.35):
            ob, centre, half = self.boxes[int(self.rng.integers(len(self.boxes)))]
            new_half = np.array([half[0], half[1], self.uniform(0.8, 2.0)])
            if self.chance(0.5):
                above = centre + np.array([0.0, 0.0, half[2] + new_half[2]])
                self.add_box(above, new_half, self.material(False), "stacked volume boxes sharing a face")
            else:
                new_half[2] = half[2]
                beside = centre + np.array([half[0] + new_half[0], 0.0, 0.0])
                self.add_box(beside, new_half, self.material(False), "volume boxes side by side sharing a face")
            return
        x, y = self.spot(margin=1.5)
        half = np.array([self.uniform(0.8, 2.5), self.uniform(0.8, 2.5), self.uniform(0.6, 2.0)])
        if shape == "cube":
            resting = self.chance(0.6)
            centre = (x, y, half[2] if resting else self.uniform(half[2] + 0.2, half[2] + 2.0))
            self.add_box(centre, half, self.material(), "volume box resting on the ground" if resting
                         else "floating volume box")
            return
        ob = self.primitive(shape, (x, y, self.uniform(1.2, 3.0)), self.material())
        ob.scale = tuple(half)
        ob.rotation_euler = tuple(self.uniform(-0.5, 0.5) for _ in range(3))
        self.feature("non-convex volume (torus)" if shape == "torus" else f"{shape.replace('_', ' ')} volume")

    def world_volume(self, scene):
        tree = scene.world.node_tree
        tree.nodes.clear()
        output = tree.nodes.new("ShaderNodeOutputWorld")
        node = tree.nodes.new("ShaderNodeVolumePrincipled")
        density = self.uniform(0.01, 0.05)
        node.inputs["Density"].default_value = density
        if self.chance(0.4):
            coords, noise, multiply = (tree.nodes.new(t) for t in (
                "ShaderNodeTexCoord", "ShaderNodeTexNoise", "ShaderNodeMath"))
            noise.inputs["Scale"].default_value = self.uniform(0.1, 0.5)
            multiply.operation = "MULTIPLY"
            multiply.inputs[1].default_value = 2.0 * density
            tree.links.new(coords.outputs["Object"], noise.inputs["Vector"])
            tree.links.new(noise.outputs["Fac"], multiply.inputs[0])
            tree.links.new(multiply.outputs[0], node.inputs["Density"])
            self.feature("noise-driven world volume")
        else:
            self.feature("world volume")
        tree.links.new(node.outputs[0], output.inputs["Volume"])

    def smoke(self, scene):
        ob = smoke_volume_object(self.bpy, scene, density=self.uniform(0.3, 1.0),
                                 material_by_nodes=self.chance(0.5))
        x, y = self.spot(margin=2.0)
        ob.location = (x, y, self.uniform(1.6, 3.0))
        ob.scale = (self.uniform(0.4, 0.8),) * 3
        ob.rotation_euler = (0.0, 0.0, self.uniform(0, math.pi))
        self.feature("OpenVDB grid from geometry nodes")
