"""The scene as ``core.media.light_paths`` needs it: its lights, the world's light, shadow
rays cast against its surfaces and media, and the camera rays whose picture ray marching can
change. Where the lighting cannot be modelled, ``scene_emitters`` says why (auto then keeps
the scene's settings)."""
from __future__ import annotations

import math

import numpy as np

from ...core.maps.camera_rays import CameraRays
from ...core.media.light_paths import WORLD_DIRECTIONS, Emitters, LightPathPredictor
from ..scene.light_sampling import emits_sampled_light, links_lights
from ..scene.probe import find_lights, linked_from, output_shader, walk_shader
from .zbuffer import _bvh, _cast, _volume_intervals

#: Camera rays the light-path prediction follows (of those whose picture ray marching can
#: change).
LIGHT_RAYS = 128


def scene_emitters(scene, depsgraph) -> tuple[Emitters | None, str | None]:
    """(the scene's lights as ``Emitters``, None) or (None, why they cannot be modelled)."""
    import bpy

    if links_lights(scene):
        return None, "the scene links lights or shadows to objects (light linking)"
    local, distant = [], []
    for light in find_lights(scene, depsgraph):
        colour = np.asarray(light.color, np.float64) * float(light.energy)
        if light.kind == "SUN":
            distant.append((-np.asarray(light.direction, np.float64), colour))
            continue
        if light.kind == "MESH":
            material = bpy.data.materials.get(light.extra.get("material", ""))
            if not emits_sampled_light(material):
                continue
            intensity = colour * math.pi * light.size ** 2          # a glowing ball of its size
        elif light.kind == "AREA":
            intensity = colour / 4.0                                 # Cycles' 1/4 of the power
        else:
            intensity = colour / (4.0 * math.pi)
        cone_cos, smooth = -1.0, 0.0
        if light.kind == "SPOT":
            cone_cos = math.cos(0.5 * light.spot_size)
            smooth = light.spot_blend * (1.0 - cone_cos)
        local.append((np.asarray(light.location, np.float64), intensity,
                      np.asarray(light.direction, np.float64), cone_cos, smooth, light.kind == "AREA"))
    reason = _unmodelled_lamp(scene)
    if reason:
        return None, reason
    groups = [0] * (len(local) + len(distant))
    background = np.zeros((2, 3))
    world = world_radiance(scene.world)
    if world is None:
        # Its strength is not known: its light is a group of its own, of radiance 1.
        distant += [(direction, np.full(3, 4.0 * math.pi / len(WORLD_DIRECTIONS))) for direction in WORLD_DIRECTIONS]
        groups += [1] * len(WORLD_DIRECTIONS)
        background[1] = 1.0
    elif np.max(world) > 0.0:
        distant += [(direction, world * 4.0 * math.pi / len(WORLD_DIRECTIONS)) for direction in WORLD_DIRECTIONS]
        groups += [0] * len(WORLD_DIRECTIONS)
        background[0] = world
    columns = list(zip(*local)) if local else [np.zeros((0, 3))] * 3 + [np.zeros(0)] * 3
    far = list(zip(*distant)) if distant else [np.zeros((0, 3))] * 2
    return Emitters(positions=np.asarray(columns[0], np.float64).reshape(-1, 3),
                    intensity=np.asarray(columns[1], np.float64).reshape(-1, 3),
                    axes=np.asarray(columns[2], np.float64).reshape(-1, 3),
                    cone_cos=np.asarray(columns[3], np.float64), cone_smooth=np.asarray(columns[4], np.float64),
                    one_sided=np.asarray(columns[5], bool),
                    toward=np.asarray(far[0], np.float64).reshape(-1, 3),
                    irradiance=np.asarray(far[1], np.float64).reshape(-1, 3),
                    group=np.asarray(groups, np.int64), background=background), None


def _unmodelled_lamp(scene) -> str | None:
    """Why a lamp's light cannot be modelled (a light node tree, an IES profile, no
    shadows), or None."""
    for ob in scene.objects:
        if ob.type != "LIGHT" or ob.hide_render:
            continue
        light = ob.data
        if getattr(light, "use_nodes", False) and light.node_tree is not None and any(
                node.type not in ("EMISSION", "OUTPUT_LIGHT") or any(linked_from(s) for s in node.inputs)
                for node in light.node_tree.nodes):
            return f"lamp '{ob.name}' is shaded by nodes"
        if not getattr(light, "use_shadow", True):
            return f"lamp '{ob.name}' casts no shadows"
    return None


def world_radiance(world) -> np.ndarray | None:
    """The world's radiance (3,) where it is one constant colour (zeros for no world),
    None where it varies or cannot be read."""
    if world is None:
        return np.zeros(3)
    if world.node_tree is None:
        return np.asarray(world.color, np.float64)
    total = np.zeros(3)
    for node, weight in walk_shader(output_shader(world.node_tree, "Surface")):
        if node.type != "BACKGROUND" or weight is None or any(linked_from(s) for s in node.inputs):
            return None
        total += weight * np.asarray(node.inputs["Color"].default_value[:3]) * node.inputs["Strength"].default_value
    return total


def shadow_caster(geometry, media):
    """``cast(origins, directions, lengths) -> (visible, segments)`` for shadow rays: no
    surface before the length, and each medium's pieces of the rays (rays may start
    inside a volume: Cycles' probe decides, as for the camera)."""
    tree = _bvh(geometry.surfaces) if len(geometry.surfaces.triangles) else None

    def cast(origins, directions, lengths):
        n = len(lengths)
        visible = np.ones(n, bool)
        if tree is not None:
            distance, _ = _cast(tree, origins.tolist(), directions.tolist(), np.minimum(lengths, 1e9).tolist())
            visible = ~(distance < lengths)
        near = np.zeros(n)
        segments = []
        for medium in media:
            if medium.kind == "world":
                segments.append((np.arange(n), near, lengths.astype(np.float64)))
            elif medium.kind == "volume_object":
                segments.append(medium.region.intervals(origins, directions, near, lengths))
            else:
                from ..scene.geometry import Triangles

                intervals, _ = _volume_intervals(geometry.volumes[medium.key],
                                                 geometry.shells.get(medium.key, Triangles.empty()),
                                                 origins, directions, near, lengths, True)
                segments.append((intervals.ray.astype(np.int64), intervals.t0, intervals.t1))
        return visible, segments
    return cast


def display_white(scene) -> float:
    """The pixel value the display shows as white (the Standard view clips there), inf for
    a view that compresses highlights (AgX, Filmic)."""
    view = scene.view_settings
    if view.view_transform == "Standard":
        return 2.0 ** (-float(view.exposure))
    return math.inf


def light_path_predictor(scene, depsgraph, rays: CameraRays, geometry, media, segments,
                         pixels: np.ndarray, emitters: Emitters, rates):
    """The light-path prediction on the sampled ``pixels`` whose picture ray marching can
    change: those crossing a medium marched in steps, or whose first surface's shadow rays
    do; up to ``LIGHT_RAYS`` of them, each standing for its share of the frame. None when
    no pixel can change."""
    origins = rays.origins.reshape(-1, 3)[pixels]
    directions = rays.directions.reshape(-1, 3)[pixels]
    near, far = rays.t_near.ravel()[pixels], rays.t_far.ravel()[pixels]
    hit = rays.hit.ravel()[pixels]
    stepped = [math.isfinite(float(m.extra.get("cycles_step", math.inf))) and m.constant_extinction() is None
               for m in media]
    # Flat ray index -> position among the sampled pixels.
    sampled = np.full(rays.origins.reshape(-1, 3).shape[0], -1, np.int64)
    sampled[pixels] = np.arange(len(pixels))
    crosses = np.zeros(len(pixels), bool)
    for m, (index, _, _) in enumerate(segments):
        rows = sampled[np.asarray(index, np.int64)]
        if stepped[m]:
            crosses[rows[rows >= 0]] = True
    cast = shadow_caster(geometry, media)
    normals = _surface_normals(geometry, origins, directions, near, far, hit)
    # A surface whose shadow rays cross a stepped medium shows its error too (a cloud's shadow).
    surface = origins + directions * far[:, None] + normals * 1e-4 * np.maximum(1.0, np.abs(far))[:, None]
    if hit.any() and emitters.count:
        direction, length, _ = emitters.shadow_rays(surface[hit])
        count = int(hit.sum())
        _, shadow_segments = cast(np.repeat(surface[hit][None], len(direction), 0).reshape(-1, 3),
                                  direction.reshape(-1, 3), length.reshape(-1))
        shaded = np.zeros(count, bool)
        for m, (index, _, _) in enumerate(shadow_segments):
            if stepped[m] and len(index):
                shaded[np.asarray(index, np.int64) % count] = True
        crosses[np.flatnonzero(hit)[shaded]] = True
    chosen = np.flatnonzero(crosses)
    if not len(chosen):
        return None
    kept = np.unique(chosen[np.linspace(0, len(chosen) - 1, min(LIGHT_RAYS, len(chosen))).round().astype(int)])
    position = np.full(len(pixels), -1, np.int64)
    position[kept] = np.arange(len(kept))
    kept_segments = []
    for index, t0, t1 in segments:
        rows = sampled[np.asarray(index, np.int64)]
        rows = np.where(rows >= 0, position[np.maximum(rows, 0)], -1)
        keep = rows >= 0
        kept_segments.append((rows[keep], np.asarray(t0)[keep], np.asarray(t1)[keep]))
    return LightPathPredictor(origins[kept], directions[kept], near[kept], far[kept], normals[kept],
                              np.full(len(kept), len(chosen) / len(kept)), media, kept_segments,
                              emitters, cast, rates=rates, max_steps=int(scene.cycles.volume_max_steps),
                              clip=display_white(scene))


def _surface_normals(geometry, origins, directions, near, far, hit) -> np.ndarray:
    """(n, 3) unit normal of the first surface each ray meets (zeros for none)."""
    normals = np.zeros((len(far), 3))
    if not hit.any() or not len(geometry.surfaces.triangles):
        return normals
    rows = np.flatnonzero(hit)
    tree = _bvh(geometry.surfaces)
    starts = origins[rows] + directions[rows] * near[rows, None]
    _, faces = _cast(tree, starts.tolist(), directions[rows].tolist(),
                     (far[rows] - near[rows] + 1e-3 * np.maximum(1.0, far[rows])).tolist(), True)
    found = faces >= 0
    tris = geometry.surfaces.vertices[geometry.surfaces.triangles[faces[found]]]
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normals[rows[found]] = n / np.maximum(np.linalg.norm(n, axis=1), 1e-30)[:, None]
    return normals
