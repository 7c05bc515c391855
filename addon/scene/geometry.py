"""What the camera rays can meet, as plain arrays: surfaces, volume boundaries and media.

One pass over the evaluated depsgraph (instances included, objects hidden from the render or
the camera left out) collects in world space every triangle that stops a camera ray (with the
medium whose face it also is), the boundary and other faces of each object volume (Cycles'
camera-in-volume probe counts them), every volume's bounding box, and the media themselves
(``VolumeMedium``, the world's first), or the reason Cycles must measure them instead. A
digest of the camera and this geometry keys the ray cache: while it holds, the Z buffer and
the media intervals on disk are right, whatever the media's densities have become."""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

from ...core.camera import CameraModel
from ...core.maps.embree_ties import cycles_world_vertices
from ...core.media.grid_nodes import grid_names
from ...core.media.ray_marching import procedural_step, voxel_step
from ...core.media.shader_graph import ShaderGraph, uses_default_coordinates
from ...core.media.volume_medium import VolumeMedium, check_densities, volume_density_scale
from .carriers import carrier, carrier_key, kept_reason
from .probe import renderable_instances
from .shader_export import export_volume_graph, has_surface, has_volume
from .volume_grids import GridReadError, volume_grids

#: Object types Cycles renders as triangle meshes.
_MESH_LIKE = ("MESH", "CURVE", "SURFACE", "FONT", "META")


@dataclass
class Triangles:
    """World-space triangles: vertices (V, 3) float64 and vertex indices (T, 3) int32.

    ``exact`` holds the vertices as Cycles computes them for its BVH, in single precision
    (``core.maps.embree_ties.cycles_world_vertices``), NaN where Cycles does otherwise
    (a mesh several objects share is instanced; a mirrored object's winding is flipped),
    and the triangles' vertex order is Cycles' own unless a mirror flipped ours."""

    vertices: np.ndarray
    triangles: np.ndarray
    exact: np.ndarray | None = None

    def __post_init__(self):
        if self.exact is None:
            self.exact = np.full(np.shape(self.vertices), np.nan, dtype=np.float32)

    @staticmethod
    def empty() -> "Triangles":
        return Triangles(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int32))

    @staticmethod
    def concatenate(parts: list["Triangles"]) -> "Triangles":
        if not parts:
            return Triangles.empty()
        offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
        return Triangles(np.concatenate([p.vertices for p in parts]),
                         np.concatenate([p.triangles + o for p, o in zip(parts, offsets)]).astype(np.int32),
                         np.concatenate([p.exact for p in parts]))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        used = self.vertices[np.unique(self.triangles)] if len(self.triangles) else self.vertices
        return used.min(axis=0), used.max(axis=0)


@dataclass
class SceneGeometry:
    """Everything camera rays can meet, in world space.

    ``surface_medium`` (T,) gives for each surface triangle the index into ``volume_keys``
    of the medium whose volume face it is too, or -1. ``volumes`` holds each mesh medium's
    boundary (its faces with the volume material), ``shells`` the other faces of the same
    object. ``volume_bounds`` are the (lo, hi) boxes of all objects with a volume.
    """

    surfaces: Triangles
    volumes: dict[str, Triangles] = field(default_factory=dict)
    shells: dict[str, Triangles] = field(default_factory=dict)
    surface_medium: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int32))
    volume_bounds: list = field(default_factory=list)
    digest: str = ""

    @property
    def volume_keys(self) -> list[str]:
        return list(self.volumes)


def _mesh_arrays(ob, cache: dict):
    """Local vertices (V, 3), loop triangles (T, 3) and their material indices of an
    evaluated object; meshes shared by several instances are read once."""
    data = getattr(ob, "data", None)
    key = data.as_pointer() if ob.type == "MESH" and data is not None else None
    if key is not None and key in cache:
        return cache[key]
    mesh = data if ob.type == "MESH" else ob.to_mesh()
    try:
        if mesh is None:
            arrays = (np.zeros((0, 3)), np.zeros((0, 3), np.int32), np.zeros(0, np.int32))
        else:
            co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
            mesh.vertices.foreach_get("co", co)
            tris = mesh.loop_triangles
            index = np.empty(len(tris) * 3, dtype=np.int32)
            tris.foreach_get("vertices", index)
            material = np.empty(len(tris), dtype=np.int32)
            tris.foreach_get("material_index", material)
            arrays = (co.reshape(-1, 3).astype(np.float64), index.reshape(-1, 3), material)
    finally:
        if ob.type != "MESH":
            ob.to_mesh_clear()
    if key is not None:
        cache[key] = arrays
    return arrays


def _to_world(vertices, triangles, matrix) -> Triangles:
    m = np.asarray(matrix, dtype=np.float64)
    world = vertices @ m[:3, :3].T + m[:3, 3]
    exact = cycles_world_vertices(vertices, m)
    if np.linalg.det(m[:3, :3]) < 0:
        # Cycles keeps normals pointing out of objects with a negative scale; so do we,
        # since the winding tells rays whether they enter or leave a volume.
        triangles = triangles[:, ::-1]
        exact = np.full_like(exact, np.nan)
    return Triangles(world, np.ascontiguousarray(triangles, dtype=np.int32), exact)


def _subset(vertices, triangles, keep) -> tuple[np.ndarray, np.ndarray]:
    if keep.all():
        return vertices, triangles
    return vertices, triangles[keep]


def scan_scene(scene, depsgraph) -> tuple[SceneGeometry, list[VolumeMedium]]:
    """Surfaces, volume boundaries and media of the evaluated scene (see module doc)."""
    media: list[VolumeMedium] = []
    graphs: dict[str, ShaderGraph] = {}

    def graph_of(tree, name) -> ShaderGraph:
        if name not in graphs:
            graphs[name] = export_volume_graph(tree)
        return graphs[name]

    world = scene.world
    if world is not None and world.node_tree is not None and has_volume(world.node_tree):
        graph = graph_of(world.node_tree, f"world:{world.name}")
        if not graph.empty:
            media.append(VolumeMedium(key=f"world:{world.name}", name=world.name, kind="world",
                                      material=None, graph=graph,
                                      extra={"cycles_step": _world_step(world), "carrier": carrier_key(world)}))
    surfaces: list[Triangles] = []
    surface_medium: list[np.ndarray] = []
    volumes: dict[str, Triangles] = {}
    shells: dict[str, Triangles] = {}
    volume_bounds: list = []
    mesh_cache: dict = {}
    made: dict = {}                 # mesh -> the Triangles made from it, by each user
    seen: dict[str, int] = {}
    kinds: dict = {}
    volume_objects: list = []

    def kind_of(material) -> tuple[bool, bool]:
        """(stops camera rays, has a volume) of a material, looked up once."""
        key = None if material is None else material.as_pointer()
        if key not in kinds:
            tree = None if material is None else material.node_tree
            kinds[key] = (has_surface(material), tree is not None and has_volume(tree))
        return kinds[key]

    for ob, matrix in renderable_instances(depsgraph):
        if ob.type not in _MESH_LIKE and ob.type != "VOLUME":
            continue
        count = seen.get(ob.name, 0)
        seen[ob.name] = count + 1
        materials = [slot.material for slot in ob.material_slots]
        volume_slots = [i for i, m in enumerate(materials) if kind_of(m)[1]]
        m = np.array(matrix, dtype=np.float64)
        if ob.type == "VOLUME":
            for i in volume_slots:
                material = materials[i]
                medium = VolumeMedium(
                    key=f"{ob.name}#{count}:{i}", name=ob.name, kind="volume_object",
                    material=material.name, graph=graph_of(material.node_tree, f"mat:{material.name}"),
                    world_to_object=np.linalg.inv(m),
                    # The evaluated volume's setting: geometry nodes that make the grids
                    # make a new volume, with the default (object space), as Cycles sees it.
                    density_scale=volume_density_scale(m, ob.data.render.space == "OBJECT"),
                    extra={"carrier": carrier_key(material)})
                volume_objects.append((medium, ob.original, m, len(volume_slots),
                                       _volume_interpolation(material)))
                media.append(medium)
            continue
        vertices, triangles, material_index = _mesh_arrays(ob, mesh_cache)
        if not len(triangles):
            continue
        if materials:
            slot = np.clip(material_index, 0, len(materials) - 1)
            surface_slot = np.array([kind_of(mat)[0] for mat in materials])
            is_surface = surface_slot[slot]
        else:
            slot = np.zeros(len(triangles), dtype=np.int32)
            is_surface = np.ones(len(triangles), dtype=bool)
        present = [i for i in volume_slots if (slot == i).any()]
        # Which medium (index into the keys made below) each face is the volume face of.
        medium_of = np.full(len(triangles), -1, dtype=np.int32)
        for n, i in enumerate(present):
            medium_of[slot == i] = len(volumes) + n
        users = made.setdefault(ob.data.as_pointer() if ob.type == "MESH" else ("own", len(made)), [])
        users.append([])
        if is_surface.any():
            surfaces.append(_to_world(*_subset(vertices, triangles, is_surface), m))
            surface_medium.append(medium_of[is_surface])
            users[-1].append(surfaces[-1])
        if present:
            volume_bounds.append(_to_world(vertices, triangles, m).bounds())
        for i in present:
            material = materials[i]
            key = f"{ob.name}#{count}:{i}"
            boundary = slot == i
            data = ob.data if ob.type == "MESH" else None
            texspace = None
            if data is not None and hasattr(data, "texspace_location"):
                texspace = (tuple(data.texspace_location), tuple(data.texspace_size))
            world_vertices = vertices @ m[:3, :3].T + m[:3, 3]
            step = procedural_step(world_vertices.min(axis=0), world_vertices.max(axis=0))
            medium = VolumeMedium(key=key, name=ob.name, kind="mesh", material=material.name,
                                  graph=graph_of(material.node_tree, f"mat:{material.name}"),
                                  world_to_object=np.linalg.inv(m), texspace=texspace,
                                  extra={"cycles_step": step * _material_step_rate(material),
                                         "carrier": carrier_key(material)})
            if len(volume_slots) > 1:
                medium.unsupported = "an object with several volume materials"
            elif _reads_attributes(medium.graph):
                medium.unsupported = "attribute or volume info nodes on a mesh volume"
            media.append(medium)
            volumes[key] = _to_world(*_subset(vertices, triangles, boundary), m)
            shells[key] = _to_world(*_subset(vertices, triangles, ~boundary), m)
            users[-1] += [volumes[key], shells[key]]
    for users in made.values():
        if len(users) > 1:          # Cycles instances a shared mesh: rays go to object space
            for part in (tris for user in users for tris in user):
                part.exact = np.full_like(part.exact, np.nan)
    # Reading grids adds (and removes) a helper object: only once the walk over the
    # depsgraph's instances is over, which that would invalidate.
    for medium, original, matrix, count, interpolation in volume_objects:
        _attach_grids(medium, scene, original, depsgraph, matrix, count, interpolation)
    for medium in media:
        check_densities(medium)
        if medium.kind == "volume_object" and medium.region is not None and not medium.region.empty:
            volume_bounds.append(medium.region.world_bounds())
    geometry = SceneGeometry(
        surfaces=Triangles.concatenate(surfaces), volumes=volumes, shells=shells,
        surface_medium=(np.concatenate(surface_medium) if surface_medium
                        else np.zeros(0, dtype=np.int32)),
        volume_bounds=volume_bounds)
    return geometry, media


def _reads_attributes(graph: ShaderGraph) -> bool:
    return any(node.type in ("ATTRIBUTE", "VOLUME_INFO") for node in graph.nodes.values())


def _volume_interpolation(material) -> str:
    settings = getattr(material, "cycles", None)
    return getattr(settings, "volume_interpolation", "LINEAR")


def _attach_grids(medium: VolumeMedium, scene, ob, depsgraph, object_to_world,
                  volume_materials: int, interpolation: str) -> None:
    """Give a volume object's medium the grids its material reads and the region Cycles
    renders, or the reason it must go to Cycles instead."""
    graph = medium.graph
    if graph.unsupported is not None:
        return
    if volume_materials > 1:
        medium.unsupported = "a volume object with several volume materials"
        return
    if any(node.type == "TEX_COORD" and "Generated" in node.props.get("used_outputs", ())
           or uses_default_coordinates(node) for node in graph.nodes.values()):
        medium.unsupported = "generated texture coordinates on a volume object"
        return
    names = grid_names(graph.nodes.values())
    try:
        grids, region = volume_grids(scene, ob, depsgraph, names, object_to_world, interpolation)
    except GridReadError as error:
        medium.unsupported = f"an OpenVDB volume object whose grids numpy cannot read: {error}"
        return
    missing = sorted(name for node in graph.nodes.values() if node.type in ("ATTRIBUTE", "VOLUME_INFO")
                     for name in grid_names([node]) if name not in grids)
    if missing:
        medium.unsupported = f"volume object reads grids it does not have ({', '.join(missing)})"
        return
    medium.grids, medium.region = grids, region
    medium.extra["cycles_step"] = _volume_object_step(ob, region) * _material_step_rate(
        _slot_material(ob, medium))


def _slot_material(ob, medium: VolumeMedium):
    return next((slot.material for slot in ob.material_slots
                 if slot.material is not None and carrier_key(slot.material) == _carrier(medium)), None)


def _carrier(medium: VolumeMedium) -> str | None:
    """The key of what carries a medium's own settings (``carriers``), None for neither."""
    if "carrier" in medium.extra:
        return medium.extra["carrier"]
    if medium.kind == "world":
        return f"world:{medium.name}"
    return None if medium.material is None else f"material:{medium.material}"


def media_by_carrier(media, keep=None) -> dict:
    """What carries each medium's own settings in Blender -> the indices of its media:
    "world:<name>" (the world's Cycles settings) or "material:<name>" (the material's,
    shared by its users; the names are full names: ``carriers``); media without either,
    whose carrier a run may not change (``kept_carriers``), or that ``keep(medium)``
    refuses, left out. ``step_setting`` reads a key's settings."""
    groups: dict = {}
    for index, medium in enumerate(media):
        key = _carrier(medium)
        if key is None or (keep is not None and not keep(medium)):
            continue
        groups.setdefault(key, []).append(index)
    return {key: tuple(members) for key, members in groups.items() if kept_reason(key) is None}


def kept_carriers(media) -> dict[str, str]:
    """The carriers of ``media`` whose settings a run may not change -> why (linked from a
    library, or a name two datablocks share): their media keep their own settings."""
    keys = dict.fromkeys(key for key in map(_carrier, media) if key is not None)
    return {key: reason for key in keys if (reason := kept_reason(key)) is not None}


def step_setting(key: str) -> tuple[object, str]:
    """Where the step of the media a key of ``estimator_choice.step_carriers`` names is set:
    (the world's Cycles settings, "volume_step_size") for "world:<name>", (the material's,
    "volume_step_rate") for "material:<name>"; the datablock found by identity
    (``carriers.carrier``)."""
    settings = carrier(key).cycles
    return settings, "volume_step_size" if key.startswith("world:") else "volume_step_rate"


def _material_step_rate(material) -> float:
    settings = getattr(material, "cycles", None)
    return float(getattr(settings, "volume_step_rate", 1.0))


def _world_step(world) -> float:
    """The world volume's Cycles step (its own size, no material rate)."""
    settings = getattr(world, "cycles", None)
    return float(getattr(settings, "volume_step_size", 1.0))


def _volume_object_step(ob, region) -> float:
    """Cycles' step of an OpenVDB volume object: the volume's own render step size when set
    (in object or world space), else its voxel size in world space."""
    if region is None:
        return float("inf")
    render = ob.data.render
    size = float(getattr(render, "step_size", 0.0))
    object_to_world = np.asarray(region.object_to_world, np.float64)
    if size > 0.0:
        if render.space == "OBJECT":
            return float(np.min(np.abs(object_to_world[:3, :3] @ np.full(3, size))))
        return size
    return voxel_step(object_to_world @ np.asarray(region.index_to_object, np.float64))


def geometry_digest(camera: CameraModel, geometry: SceneGeometry) -> str:
    """A hash of everything the rays depend on: camera, surfaces, volume boundaries."""
    digest = hashlib.blake2b(digest_size=16)
    for name in ("kind", "width", "height", "lens", "sensor_width", "sensor_height", "sensor_fit",
                 "ortho_scale", "shift_x", "shift_y", "clip_start", "clip_end",
                 "pixel_aspect_x", "pixel_aspect_y", "border"):
        digest.update(repr(getattr(camera, name)).encode())
    digest.update(np.ascontiguousarray(camera.matrix_world, dtype=np.float64).tobytes())
    keys = sorted(geometry.volumes)
    for tris in ([geometry.surfaces] + [geometry.volumes[k] for k in keys]
                 + [geometry.shells[k] for k in keys if k in geometry.shells]):
        digest.update(np.ascontiguousarray(tris.vertices, dtype=np.float32).tobytes())
        digest.update(np.ascontiguousarray(tris.triangles).tobytes())
    digest.update(repr(keys).encode())
    digest.update(np.ascontiguousarray(geometry.surface_medium, dtype=np.int32).tobytes())
    # Volume objects' boxes: their voxels may move the camera-in-volume gate.
    digest.update(repr([(tuple(np.round(lo, 6)), tuple(np.round(hi, 6)))
                        for lo, hi in geometry.volume_bounds]).encode())
    return digest.hexdigest()
