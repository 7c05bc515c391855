"""A seeded generator of lit scenes with participating media, as artists build them: the
suite that judges ``--estimator auto`` against the file's own settings on the image
(``bench/bench_auto_lit.py``, ``tests/test_auto_lit.py``).

Each seed draws one kind (``KINDS[seed % len(KINDS)]``, so every kind comes round every
eight seeds) and the rest from ``numpy.random.default_rng(seed)``:

* world fog: a world Principled Volume, homogeneous or noise-textured (camera inside it);
* fog box: a box resting on the floor, homogeneous or noise-textured; sometimes so large the
  camera stands in it;
* fog blob: a sphere or squashed blob, floating or resting, homogeneous or noise;
* dense cloud: a self-shadowing noise cloud (optical depth 8-80 across), fading out or dense
  to its edge, lit by a sun and a sky, the camera outside (issue 43's first failure);
* emissive volume: noise-textured Principled Volume emission or blackbody, with or without a
  lamp inside;
* smoke grid: an OpenVDB density grid made by geometry nodes (``xmap_scenes.smoke_volume_object``);
* smoke in fog: a smoke grid or noise blob inside a world fog or a large fog box;
* world water: a homogeneous world medium of scattering and absorption under a sun from
  above and a spot lamp (issue 43's second failure).

Densities span two decades (optical depth 0.1-10 across a medium, the cloud denser), albedo
and anisotropy vary; one to three lamps (sun, point, spot, area) and always a world light:
a constant colour, a Sky Texture or a vertical gradient. A floor and a few surfaces. The
settings are a new Blender 5 file's: Cycles on the CPU, its default samples (4096,
adaptive), blue noise (``AUTOMATIC``), null scattering, OIDN on, AgX.

``GENERATOR_VERSION`` names what the seeds build: bump it when a seed's content changes,
so saved scenes (and the references cached under their bytes' hash) are made again.
"""
from __future__ import annotations

import json
import math
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from support.xmap_scenes import smoke_volume_object

GENERATOR_VERSION = 1
KINDS = ("world fog", "fog box", "fog blob", "dense cloud", "emissive volume", "smoke grid",
         "smoke in fog", "world water")
WIDTH, HEIGHT = 320, 180
LAMP_KINDS = ("SUN", "POINT", "SPOT", "AREA")
#: A world medium's optical depth is drawn over this distance (the scenes' depth, metres).
WORLD_DEPTH = 20.0
EXAMPLE_BLENDS = Path(__file__).resolve().parents[2] / "example_blends"


@dataclass
class LitScene:
    """What one seed built: its kind and, in words, what it holds."""

    seed: int
    kind: str
    features: list[str] = field(default_factory=list)
    size: tuple[int, int] = (WIDTH, HEIGHT)

    def describe(self) -> str:
        return f"seed {self.seed} ({self.kind}): " + ", ".join(self.features)

    def to_json(self) -> dict:
        return {**asdict(self), "size": list(self.size), "generator": GENERATOR_VERSION}


def kind_of(seed: int) -> str:
    return KINDS[seed % len(KINDS)]


def build_lit_scene(bpy, seed: int, width: int = WIDTH, height: int = HEIGHT) -> LitScene:
    """Replace the session's scene with the one ``seed`` draws (see the module notes)."""
    if str(EXAMPLE_BLENDS) not in sys.path:
        sys.path.insert(0, str(EXAMPLE_BLENDS))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    # The factory startup's scene predates blue noise; a scene made in Blender 5 has it.
    scene.cycles.sampling_pattern = "AUTOMATIC"
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    built = LitScene(seed, kind_of(seed), size=(width, height))
    _Builder(bpy, scene, np.random.default_rng(seed), built).build()
    bpy.context.view_layer.update()
    return built


def saved_lit_scene(bpy, seed: int, folder: Path, width: int = WIDTH, height: int = HEIGHT
                    ) -> tuple[Path, LitScene]:
    """The seed's scene saved as a .blend in ``folder`` (built and saved once: a .blend's
    bytes differ from one save to the next, and a reference is cached under them), with its
    description beside it."""
    from xsl_render.core.files import atomic_path, write_json

    stem = f"lit_{seed:03d}_v{GENERATOR_VERSION}_{width}x{height}"
    path, about = Path(folder) / f"{stem}.blend", Path(folder) / f"{stem}.json"
    if path.is_file() and about.is_file():
        data = json.loads(about.read_text())
        return path, LitScene(data["seed"], data["kind"], data["features"], tuple(data["size"]))
    built = build_lit_scene(bpy, seed, width, height)
    with atomic_path(path) as tmp:
        bpy.ops.wm.save_as_mainfile(filepath=str(tmp), compress=True, check_existing=False)
    write_json(about, built.to_json())
    return path, built


class _Builder:
    def __init__(self, bpy, scene, rng, out: LitScene):
        self.bpy, self.scene, self.rng, self.out = bpy, scene, rng, out
        import _scene_kit as kit

        self.kit = kit
        self.target = np.array([0.0, 0.0, 1.2])        # what the camera and the lamps aim at

    # --- draws --------------------------------------------------------------------
    def uniform(self, lo, hi) -> float:
        return float(self.rng.uniform(lo, hi))

    def log_uniform(self, lo, hi) -> float:
        return float(10 ** self.rng.uniform(math.log10(lo), math.log10(hi)))

    def chance(self, p) -> bool:
        return bool(self.rng.random() < p)

    def pick(self, items):
        return items[int(self.rng.integers(len(items)))]

    def feature(self, text: str) -> None:
        self.out.features.append(text)

    # --- the scene ----------------------------------------------------------------
    def build(self) -> None:
        kind = self.out.kind
        getattr(self, "kind_" + kind.replace(" ", "_"))()
        self.floor_and_surfaces()
        if not any(ob.type == "CAMERA" for ob in self.scene.objects):
            self.camera_outside()

    def kind_world_fog(self):
        extinction = self.log_uniform(0.1, 10.0) / WORLD_DEPTH
        self.world_light()
        self.world_medium(extinction, noise=self.chance(0.5))
        self.lamps(int(self.rng.integers(1, 4)))
        self.camera_outside(distance=(7, 12))
        self.feature("camera inside the medium (world)")

    def kind_fog_box(self):
        inside = self.chance(0.35)
        if inside:
            half = np.array([self.uniform(6, 10), self.uniform(8, 12), self.uniform(2.5, 4)])
            centre = np.array([0.0, self.uniform(-3, 0), half[2]])
        else:
            half = np.array([self.uniform(1.5, 4), self.uniform(1.5, 4), self.uniform(0.8, 2.5)])
            centre = np.array([self.uniform(-1, 1), self.uniform(-1, 1), half[2]])
        self.target = np.array([centre[0], centre[1] + (4 if inside else 0), min(1.2, half[2])])
        material = self.medium_material("Fog", self.optical_depth() / (2 * half[:2].mean()),
                                        noise=self.chance(0.6))
        self.box("Fog Box", centre, half, material)
        self.feature(f"fog box {2 * half[0]:.1f} x {2 * half[1]:.1f} x {2 * half[2]:.1f} m resting on the floor")
        self.world_light()
        self.lamps(int(self.rng.integers(1, 4)))
        if inside:
            self.camera_at(np.array([self.uniform(-1, 1), centre[1] - half[1] + self.uniform(2, 4),
                                     self.uniform(1.2, min(2.2, 2 * half[2] - 0.3))]))
            self.feature("camera inside the medium")

    def kind_fog_blob(self):
        self.blob("Fog Blob", self.optical_depth(), noise=self.chance(0.6))
        self.world_light()
        self.lamps(int(self.rng.integers(1, 4)))

    def kind_dense_cloud(self):
        radius = self.uniform(1.8, 3.0)
        centre = np.array([self.uniform(-1, 1), self.uniform(-1, 1), radius * 0.8 + self.uniform(0.8, 2.0)])
        self.target = centre
        depth = self.log_uniform(8.0, 80.0)
        # Half the clouds fade out towards their sphere; the rest end at it, dense up to the
        # edge (every camera ray then sees almost no transmittance: issue 43's case).
        soft = self.chance(0.5)
        material = self.medium_material("Cloud", depth / (2 * radius), noise=True, falloff=soft,
                                         albedo=(0.9, 1.0), anisotropy=(0.0, 0.8))
        squash = self.uniform(0.6, 0.9)
        self.kit.mesh_object("Cloud", self.kit.uv_sphere(1.0, 32, 16), material, location=tuple(centre),
                             scale=(radius, radius * self.uniform(0.8, 1.1), radius * squash))
        self.feature(f"dense self-shadowing noise cloud, radius {radius:.1f} m, optical depth {depth:.0f} across, "
                     + ("fading out" if soft else "dense to its edge"))
        self.sun(elevation=(20, 70))
        self.world_light(sky=True)
        self.lamps(int(self.rng.integers(0, 2)))

    def kind_emissive_volume(self):
        lamp_inside = self.chance(0.5)
        ob = self.blob("Glow", self.optical_depth(), noise=True, emissive=True)
        self.world_light(dim=True)
        if lamp_inside:
            self.lamp("POINT", location=np.array(ob.location), energy=self.log_uniform(50, 600))
            self.feature("a point lamp inside the volume")
        self.lamps(int(self.rng.integers(0, 2)))

    def kind_smoke_grid(self):
        self.smoke(self.optical_depth())
        self.world_light()
        self.lamps(int(self.rng.integers(1, 4)))

    def kind_smoke_in_fog(self):
        if self.chance(0.5):
            self.world_light()
            self.world_medium(self.log_uniform(0.1, 2.0) / WORLD_DEPTH, noise=False)
        else:
            half = np.array([self.uniform(7, 10), self.uniform(9, 12), self.uniform(3, 5)])
            material = self.medium_material("Fog", self.log_uniform(0.1, 2.0) / (2 * half[:2].mean()),
                                            noise=False)
            self.box("Fog Box", np.array([0.0, 0.0, half[2]]), half, material)
            self.feature("a large fog box around the scene")
            self.world_light()
        if self.chance(0.5):
            self.smoke(self.optical_depth())
        else:
            self.blob("Smoke Blob", self.optical_depth(), noise=True)
        self.lamps(int(self.rng.integers(1, 4)))
        self.camera_outside(distance=(6, 9))
        self.feature("camera inside the outer medium")

    def kind_world_water(self):
        scatter = self.log_uniform(0.03, 0.4)
        absorb = self.log_uniform(0.02, 0.2)
        anisotropy = self.uniform(0.3, 0.9)
        tint = (self.uniform(0.05, 0.4), self.uniform(0.5, 0.9), self.uniform(0.6, 1.0))
        tree = self.world_light(colour=(0.02, 0.08, 0.12))
        new, link = tree.nodes.new, tree.links.new
        output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld")
        volume_scatter, absorption, both = new("ShaderNodeVolumeScatter"), new("ShaderNodeVolumeAbsorption"), \
            new("ShaderNodeAddShader")
        volume_scatter.inputs["Density"].default_value = scatter
        volume_scatter.inputs["Anisotropy"].default_value = anisotropy
        absorption.inputs["Color"].default_value = (*tint, 1.0)
        absorption.inputs["Density"].default_value = absorb
        link(volume_scatter.outputs[0], both.inputs[0])
        link(absorption.outputs[0], both.inputs[1])
        link(both.outputs[0], output.inputs["Volume"])
        self.feature(f"homogeneous world water: scattering {scatter:.3f}/m (g {anisotropy:.2f}), "
                     f"absorption {absorb:.3f}/m of colour ({tint[0]:.2f}, {tint[1]:.2f}, {tint[2]:.2f})")
        self.sun(elevation=(60, 88))
        self.lamp("SPOT", energy=self.log_uniform(500, 4000))
        self.lamps(int(self.rng.integers(0, 2)))
        self.camera_outside(distance=(6, 10))
        self.feature("camera inside the medium (world)")

    # --- media --------------------------------------------------------------------
    def optical_depth(self) -> float:
        """Optical depth across a medium: two decades, 0.1 to 10."""
        return self.log_uniform(0.1, 10.0)

    def medium_material(self, name, extinction, noise, falloff=False, emissive=False,
                        albedo=(0.3, 0.99), anisotropy=(-0.3, 0.85)):
        """A Principled Volume whose density is the extinction (its absorption colour black:
        Cycles' extinction is then the density whatever the colour, and the colour is the
        albedo), constant or driven by a Noise Texture (mean about ``extinction``), with a
        spherical falloff to round a cloud's edges."""
        material = self.bpy.data.materials.new(name)
        tree = material.node_tree
        tree.nodes.clear()
        new, link = tree.nodes.new, tree.links.new
        output = new("ShaderNodeOutputMaterial")
        grey = self.uniform(*albedo)
        colour = tuple(min(1.0, grey * self.uniform(0.85, 1.15)) for _ in range(3))
        g = self.uniform(*anisotropy)
        node = self.kit.principled_volume_node(tree, "Medium", extinction, colour, g)
        words = [f"{'noise-textured' if noise else 'homogeneous'} {extinction:.3g}/m",
                 f"albedo {grey:.2f}", f"g {g:.2f}"]
        if noise:
            coords, texture, ramp = new("ShaderNodeTexCoord"), new("ShaderNodeTexNoise"), new("ShaderNodeMapRange")
            texture.inputs["Scale"].default_value = self.uniform(1.0, 3.0)
            texture.inputs["Detail"].default_value = self.uniform(1.0, 6.0)
            low = self.uniform(0.3, 0.48)
            ramp.inputs["From Min"].default_value = low
            ramp.inputs["From Max"].default_value = low + self.uniform(0.15, 0.3)
            link(coords.outputs["Object"], texture.inputs["Vector"])
            link(texture.outputs[0], ramp.inputs["Value"])
            density = new("ShaderNodeMath")
            density.operation = "MULTIPLY"
            density.inputs[1].default_value = 2.0 * extinction
            link(ramp.outputs["Result"], density.inputs[0])
            if falloff:
                sphere, edge, shaped = new("ShaderNodeTexGradient"), new("ShaderNodeMapRange"), new("ShaderNodeMath")
                sphere.gradient_type = "SPHERICAL"
                edge.inputs["From Max"].default_value = 0.5
                shaped.operation = "MULTIPLY"
                link(coords.outputs["Object"], sphere.inputs["Vector"])
                link(sphere.outputs[0], edge.inputs["Value"])
                link(density.outputs[0], shaped.inputs[0])
                link(edge.outputs["Result"], shaped.inputs[1])
                density = shaped
            link(density.outputs[0], node.inputs["Density"])
        if emissive:
            if self.chance(0.5):
                strength = self.log_uniform(0.03, 0.4)
                tint = tuple(self.uniform(0.3, 1.0) for _ in range(3))
                node.inputs["Emission Strength"].default_value = strength
                node.inputs["Emission Color"].default_value = (*tint, 1.0)
                words.append(f"emission {strength:.2f}")
            else:
                intensity, kelvin = self.log_uniform(0.2, 2.0), self.uniform(1200, 3500)
                node.inputs["Blackbody Intensity"].default_value = intensity
                node.inputs["Temperature"].default_value = kelvin
                words.append(f"blackbody {intensity:.2f} at {kelvin:.0f} K")
        link(node.outputs[0], output.inputs["Volume"])
        self.feature(f"{name.lower()}: " + ", ".join(words))
        return material

    def world_medium(self, extinction, noise):
        tree = self.scene.world.node_tree
        output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld")
        g, grey = self.uniform(-0.2, 0.8), self.uniform(0.5, 0.99)
        node = self.kit.principled_volume_node(tree, "Fog", extinction, (grey, grey, grey), g)
        if noise:
            new, link = tree.nodes.new, tree.links.new
            coords, texture, density = new("ShaderNodeTexCoord"), new("ShaderNodeTexNoise"), new("ShaderNodeMath")
            texture.inputs["Scale"].default_value = self.uniform(0.1, 0.4)
            texture.inputs["Detail"].default_value = self.uniform(1.0, 4.0)
            density.operation = "MULTIPLY"
            density.inputs[1].default_value = 2.0 * extinction
            link(coords.outputs["Object"], texture.inputs["Vector"])
            link(texture.outputs[0], density.inputs[0])
            link(density.outputs[0], node.inputs["Density"])
        tree.links.new(node.outputs[0], output.inputs["Volume"])
        self.feature(f"{'noise' if noise else 'homogeneous'} world fog {extinction:.3g}/m, "
                     f"albedo {grey:.2f}, g {g:.2f}")

    def box(self, name, centre, half, material):
        kit = self.kit
        return kit.mesh_object(name, lambda bm: kit.box(bm, tuple(2 * half)), material, location=tuple(centre))

    def blob(self, name, depth, noise, emissive=False):
        """A sphere or squashed blob, floating or resting on the floor."""
        radius = self.uniform(0.8, 2.2)
        scale = np.array([radius, radius * self.uniform(0.7, 1.3), radius * self.uniform(0.5, 1.1)])
        resting = self.chance(0.4)
        centre = np.array([self.uniform(-1.5, 1.5), self.uniform(-1.5, 1.5),
                           scale[2] if resting else scale[2] + self.uniform(0.3, 1.5)])
        self.target = centre
        material = self.medium_material(name, depth / (2 * scale.mean()), noise, falloff=noise and self.chance(0.5),
                                        emissive=emissive)
        ob = self.kit.mesh_object(name, self.kit.uv_sphere(1.0, 32, 16), material, location=tuple(centre),
                                  scale=tuple(scale))
        self.feature(f"{'resting' if resting else 'floating'} blob of {2 * radius:.1f} m, optical depth "
                     f"{depth:.2g} across")
        return ob

    def smoke(self, depth):
        """An OpenVDB grid from geometry nodes (noise density about 0.5 of the material's,
        4 m across before scaling), its scattering colour and anisotropy drawn."""
        size = self.uniform(0.5, 0.9)
        density = depth / (4 * size * 0.5)
        ob = smoke_volume_object(self.bpy, self.scene, density=density, material_by_nodes=self.chance(0.5))
        ob.scale = (size,) * 3
        ob.location = (self.uniform(-1, 1), self.uniform(-1, 1), 1.5 * size + self.uniform(0.0, 1.0))
        ob.rotation_euler = (0.0, 0.0, self.uniform(0, math.pi))
        material = ob.material_slots[0].material or ob.data.materials[0]
        node = material.node_tree.nodes["Principled Volume"]
        grey, g = self.uniform(0.3, 0.95), self.uniform(-0.2, 0.8)
        node.inputs["Color"].default_value = (grey, grey, grey, 1.0)
        node.inputs["Anisotropy"].default_value = g
        self.target = np.array(ob.location)
        self.feature(f"OpenVDB smoke grid (geometry nodes), {4 * size:.1f} m, optical depth {depth:.2g} "
                     f"across, albedo {grey:.2f}, g {g:.2f}")

    # --- lights -------------------------------------------------------------------
    def world_light(self, sky=False, dim=False, colour=None):
        """The world's light: a constant colour, a Sky Texture or a vertical gradient
        (``sky``: a Sky Texture or a constant blue sky). Returns the world's node tree."""
        world = self.bpy.data.worlds.new("World")
        self.scene.world = world
        tree = world.node_tree
        new, link = tree.nodes.new, tree.links.new
        background = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
        choice = self.rng.random()
        if colour is not None:
            strength = self.uniform(0.3, 1.5)
            background.inputs["Color"].default_value = (*colour, 1.0)
            self.feature(f"world colour ({colour[0]:.2f}, {colour[1]:.2f}, {colour[2]:.2f}) x {strength:.2f}")
        elif (sky and choice < 0.5) or (not sky and choice < 0.25):
            texture = new("ShaderNodeTexSky")
            texture.sky_type = "MULTIPLE_SCATTERING"
            texture.sun_disc = self.chance(0.5)
            texture.sun_elevation = math.radians(self.uniform(15, 70))
            texture.sun_rotation = math.radians(self.uniform(0, 360))
            # Its sun disc is a sun's worth of light: a daylight sky is metres of exposure
            # brighter than the constant worlds.
            strength = self.log_uniform(0.01, 0.05) if texture.sun_disc else self.log_uniform(0.03, 0.15)
            link(texture.outputs[0], background.inputs["Color"])
            self.feature(f"Sky Texture{' with its sun disc' if texture.sun_disc else ''} x {strength:.2f}")
        elif not sky and choice < 0.45:
            coords, axes, ramp = new("ShaderNodeTexCoord"), new("ShaderNodeSeparateXYZ"), new("ShaderNodeValToRGB")
            ramp.color_ramp.elements[0].color = (*self.colour(0.2, 0.6), 1.0)
            ramp.color_ramp.elements[1].color = (*self.colour(0.1, 0.5, blue=True), 1.0)
            link(coords.outputs["Generated"], axes.inputs[0])
            link(axes.outputs["Z"], ramp.inputs["Fac"])
            link(ramp.outputs["Color"], background.inputs["Color"])
            strength = self.uniform(0.2, 1.0)
            self.feature(f"gradient sky x {strength:.2f}")
        else:
            tint = self.colour(0.05, 0.5, blue=sky)
            strength = self.uniform(0.3, 1.0)
            background.inputs["Color"].default_value = (*tint, 1.0)
            self.feature(f"world colour ({tint[0]:.2f}, {tint[1]:.2f}, {tint[2]:.2f}) x {strength:.2f}")
        background.inputs["Strength"].default_value = strength * (0.2 if dim else 1.0)
        return tree

    def colour(self, lo, hi, blue=False):
        value = [self.uniform(lo, hi) for _ in range(3)]
        if blue:
            value = sorted(value)
        return tuple(value)

    def lamps(self, count: int):
        for _ in range(count):
            kind = self.pick(LAMP_KINDS)
            if kind == "SUN":
                self.sun()
            else:
                self.lamp(kind)

    def sun(self, elevation=(15, 80)):
        strength = self.uniform(1.0, 4.0)
        tilt, turn = 90.0 - self.uniform(*elevation), self.uniform(0, 360)
        self.kit.add_light("Sun", "SUN", (0, 0, 10), strength,
                           rotation=(math.radians(tilt), 0.0, math.radians(turn)), angle=math.radians(0.5))
        self.feature(f"sun {strength:.1f} at {90 - tilt:.0f} deg")

    def lamp(self, kind, location=None, energy=None):
        """A point, spot or area lamp near the target, the spot and area aimed at it."""
        if location is None:
            distance = self.uniform(2.5, 6.0)
            angle = self.uniform(0, 2 * math.pi)
            location = self.target + np.array([distance * math.cos(angle), distance * math.sin(angle),
                                               self.uniform(1.0, 5.0)])
        if energy is None:
            energy = self.log_uniform(*{"POINT": (100, 2000), "SPOT": (300, 4000), "AREA": (100, 1500)}[kind])
        props = {}
        if kind == "SPOT":
            props = {"spot_size": math.radians(self.uniform(30, 90)), "spot_blend": self.uniform(0.05, 0.5)}
        elif kind == "AREA":
            props = {"size": self.uniform(0.5, 2.5)}
        target = tuple(self.target) if kind in ("SPOT", "AREA") else None
        self.kit.add_light(kind.title(), kind, tuple(location), energy, radius=self.uniform(0.05, 0.4),
                           target=target, **props)
        self.feature(f"{kind.lower()} {energy:.0f} W at ({location[0]:.1f}, {location[1]:.1f}, {location[2]:.1f})")

    # --- floor, surfaces, camera --------------------------------------------------
    def floor_and_surfaces(self):
        kit = self.kit
        grey = self.uniform(0.15, 0.7)
        kit.mesh_object("Floor", kit.plane(60.0, 60.0), kit.surface_material("Floor", (grey, grey, grey), 0.6))
        shapes = {"cube": lambda bm: kit.box(bm, (1.0, 1.0, 1.0), (0.0, 0.0, 0.5)),
                  "sphere": lambda bm: kit.uv_sphere(0.5, 24, 12)(bm),
                  "pillar": kit.cylinder(0.3, 2.5, 16, (0.0, 0.0, 1.25))}
        for index in range(int(self.rng.integers(1, 4))):
            shape = self.pick(tuple(shapes))
            spot = self.target[:2] + np.array([self.uniform(-4, 4), self.uniform(-3, 5)])
            scale = self.uniform(0.6, 1.6)
            lift = 0.5 * scale if shape == "sphere" else 0.0
            material = kit.surface_material(f"Surface.{index}", self.colour(0.1, 0.9), self.uniform(0.2, 0.9),
                                            metallic=1.0 if self.chance(0.15) else 0.0)
            kit.mesh_object(f"{shape.title()}.{index}", shapes[shape], material,
                            location=(float(spot[0]), float(spot[1]), lift), rotation=(0, 0, self.uniform(0, 3)),
                            scale=(scale,) * 3)
            self.feature(f"a {shape}")

    def camera_outside(self, distance=(7, 13)):
        away = self.uniform(*distance)
        turn = math.radians(self.uniform(-40, 40))
        eye = self.target + np.array([away * math.sin(turn), -away * math.cos(turn), self.uniform(0.3, 2.5)])
        eye[2] = max(eye[2], 0.6)
        self.camera_at(eye)

    def camera_at(self, eye):
        lens = self.uniform(24, 50)
        ob = self.kit.add_camera("Camera", tuple(eye), tuple(self.target), lens=lens, clip_end=100.0)
        ob.rotation_euler.y += math.radians(self.uniform(-3, 3))
        self.feature(f"camera {lens:.0f} mm")
