"""The 0-LightMap of section 4.4: the visible light sources drawn on black, in HDR.

Each light is drawn where the eye sees it at its projected size (point and spot lights as
discs, a spot only with the camera in its cone; area lights as their shape; the sun as a
disc; emissive meshes from the frame's Emit pass), as the light that reaches the eye from it
(irradiance at the eye times the medium's transmittance on the way) spread over its pixels,
so a light's integral is its share whatever its size on screen. A pixel is drawn only where
the first surface lies behind the light (the paper's admitted weakness: occluded lights)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..camera import CameraModel
from ..media.scene_model import LightSource, luminance

#: Subsamples per pixel side when measuring how much of a pixel a light covers.
SUPERSAMPLE = 4
#: A surface occludes a light only if it is nearer than the light by more than this
#: fraction of the light's distance (or its radius): bulbs and headlight glass around a
#: lamp must not hide it.
OCCLUSION_SLACK = 0.03


@dataclass
class DrawnLight:
    """What the 0-LightMap did with one light (reported in maps.json)."""

    name: str
    kind: str
    drawn: bool
    reason: str
    pixels: float = 0.0            # covered area in pixels (fractional)
    visible_fraction: float = 0.0  # of the projected footprint, after occlusion
    irradiance: float = 0.0        # at the eye, before the medium (W/m^2, luminance)
    transmittance: float = 1.0
    optical_depth: float = 0.0


def _smoothstep(edge0: float, edge1: float, x: float) -> float:
    if edge1 <= edge0:
        return 1.0 if x >= edge0 else 0.0
    t = min(max((x - edge0) / (edge1 - edge0), 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def spot_weight(light: LightSource, eye: np.ndarray) -> float:
    """Cycles' spot attenuation toward the eye: 0 outside the cone, smooth at its edge."""
    to_eye = eye - np.asarray(light.location)
    distance = np.linalg.norm(to_eye)
    if distance == 0:
        return 1.0
    cos_angle = float(np.dot(to_eye / distance, np.asarray(light.direction)))
    cos_half = math.cos(0.5 * (light.spot_size or math.pi))
    if cos_angle <= cos_half:
        return 0.0
    smooth = (1.0 - cos_half) * (light.spot_blend or 0.0)
    return _smoothstep(0.0, smooth, cos_angle - cos_half) if smooth > 0 else 1.0


def _intensity(light: LightSource, eye: np.ndarray) -> float:
    """Radiant intensity toward the eye (W/sr; sun: irradiance), luminance of the colour."""
    colour = luminance(light.color)
    if light.kind == "POINT":
        return light.energy / (4 * math.pi) * colour
    if light.kind == "SPOT":
        return light.energy / (4 * math.pi) * colour * spot_weight(light, eye)
    if light.kind == "AREA":
        to_eye = eye - np.asarray(light.location)
        facing = float(np.dot(to_eye, np.asarray(light.direction))) / max(np.linalg.norm(to_eye), 1e-12)
        return light.energy / math.pi * colour * max(facing, 0.0)
    if light.kind == "SUN":
        return light.energy * colour
    raise ValueError(f"not a lamp: {light.kind}")


def _subsample_grid(row0: int, row1: int, col0: int, col1: int) -> tuple[np.ndarray, np.ndarray]:
    offsets = (np.arange(SUPERSAMPLE) + 0.5) / SUPERSAMPLE
    rows = (np.arange(row0, row1)[:, None] + offsets[None, :]).ravel()
    cols = (np.arange(col0, col1)[:, None] + offsets[None, :]).ravel()
    return np.meshgrid(rows, cols, indexing="ij")


def _coverage(inside: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    h, w = shape
    return inside.reshape(h, SUPERSAMPLE, w, SUPERSAMPLE).mean(axis=(1, 3))


def _footprint_disc(camera: CameraModel, centre_col: float, centre_row: float, radius_px: float):
    """(row0, col0, coverage) of a disc, clipped to the frame; None if outside."""
    radius_px = max(radius_px, 0.5 / SUPERSAMPLE)
    row0 = max(int(math.floor(centre_row - radius_px)), 0)
    row1 = min(int(math.ceil(centre_row + radius_px)) + 1, camera.height)
    col0 = max(int(math.floor(centre_col - radius_px)), 0)
    col1 = min(int(math.ceil(centre_col + radius_px)) + 1, camera.width)
    if row1 <= row0 or col1 <= col0:
        return None
    rr, cc = _subsample_grid(row0, row1, col0, col1)
    inside = (rr - centre_row) ** 2 + (cc - centre_col) ** 2 <= radius_px ** 2
    coverage = _coverage(inside, (row1 - row0, col1 - col0))
    if not inside.any():
        # Smaller than a subsample: keep its area in the pixel that holds its centre.
        r, c = int(centre_row), int(centre_col)
        if not (0 <= r < camera.height and 0 <= c < camera.width):
            return None
        coverage = np.zeros((row1 - row0, col1 - col0))
        coverage[r - row0, c - col0] = math.pi * radius_px ** 2
    return row0, col0, coverage


def _footprint_polygon(camera: CameraModel, corners: np.ndarray):
    """(row0, col0, coverage) of a convex polygon of world points; None if not in view."""
    col, row, depth = camera.project(corners)
    if (depth <= camera.clip_start).any():
        return None
    row0 = max(int(math.floor(row.min())), 0)
    row1 = min(int(math.ceil(row.max())) + 1, camera.height)
    col0 = max(int(math.floor(col.min())), 0)
    col1 = min(int(math.ceil(col.max())) + 1, camera.width)
    if row1 <= row0 or col1 <= col0:
        return None
    rr, cc = _subsample_grid(row0, row1, col0, col1)
    inside = np.ones(rr.shape, dtype=bool)
    sign = None
    for i in range(len(corners)):
        r1, c1, r2, c2 = row[i], col[i], row[(i + 1) % len(corners)], col[(i + 1) % len(corners)]
        cross = (c2 - c1) * (rr - r1) - (r2 - r1) * (cc - c1)
        if sign is None:
            sign = 1.0 if np.sum(cross >= 0) >= np.sum(cross < 0) else -1.0
        inside &= cross * sign >= 0
    return row0, col0, _coverage(inside, (row1 - row0, col1 - col0))


def _area_corners(light: LightSource, axes: np.ndarray, segments: int = 24) -> np.ndarray:
    """World-space outline of an area light (its local X/Y axes given)."""
    half_x, half_y = 0.5 * light.size, 0.5 * (light.size_y or light.size)
    centre = np.asarray(light.location)
    if light.shape in ("DISK", "ELLIPSE"):
        t = np.linspace(0, 2 * math.pi, segments, endpoint=False)
        local = np.stack([half_x * np.cos(t), half_y * np.sin(t)], axis=1)
    else:
        local = np.array([[-half_x, -half_y], [half_x, -half_y], [half_x, half_y], [-half_x, half_y]])
    return centre + local[:, :1] * axes[0] + local[:, 1:] * axes[1]


def _perpendicular_axes(direction: np.ndarray) -> np.ndarray:
    d = direction / max(np.linalg.norm(direction), 1e-12)
    helper = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, d)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(d, x)])


@dataclass
class Footprint:
    """One light source in the 0-LightMap: its pixels and what reaches the eye from them.

    ``values`` (a patch placed at ``row0, col0``) sum to the light's irradiance at the eye
    times the transmittance; ``optical_depth`` is tau between the eye and the light.
    """

    name: str
    row0: int
    col0: int
    values: np.ndarray
    optical_depth: float

    @property
    def mass(self) -> float:
        return float(self.values.sum())

    def place(self, shape: tuple[int, int], scale: float = 1.0, out: np.ndarray | None = None) -> np.ndarray:
        out = np.zeros(shape, dtype=np.float64) if out is None else out
        h, w = self.values.shape
        out[self.row0:self.row0 + h, self.col0:self.col0 + w] += scale * self.values
        return out


def lamp_footprints(camera: CameraModel, lights: list[LightSource], distance: np.ndarray,
                    transmittance_to: Callable[[np.ndarray], np.ndarray],
                    ) -> tuple[list[Footprint], list[DrawnLight]]:
    """The footprint of every lamp the eye can see, and why each lamp was or was not drawn.

    Parameters
    ----------
    camera : the camera model (full frame, row 0 at the top).
    lights : lamps (emissive meshes come from :func:`emission_footprints`; MESH entries are skipped).
    distance : (H, W) distance along each pixel's ray to the first surface, ``inf`` for none.
    transmittance_to : maps world points (N, 3) to exp(-tau) from the eye to each point.
    """
    footprints, report = [], []
    eye = camera.eye
    for light in lights:
        if light.kind == "MESH":
            continue
        entry = DrawnLight(light.name, light.kind, False, "")
        report.append(entry)
        intensity = _intensity(light, eye)
        if intensity <= 0:
            entry.reason = "outside its cone" if light.kind == "SPOT" else "emits nothing toward the camera"
            continue
        if light.kind == "SUN":
            footprint, light_distance, point = _sun_footprint(camera, light)
            irradiance = intensity                      # a sun lamp's strength is irradiance
        else:
            footprint, light_distance, point = _lamp_footprint(camera, light)
            irradiance = intensity / max(light_distance, 1e-9) ** 2
        if footprint is None:
            entry.reason = "not in the frame"
            continue
        row0, col0, coverage = footprint
        h, w = coverage.shape
        window = distance[row0:row0 + h, col0:col0 + w]
        if light.kind == "SUN":
            unoccluded = np.isinf(window)          # only where the eye sees the sky
        else:
            slack = max(OCCLUSION_SLACK * light_distance, 2.0 * light.size)
            unoccluded = window >= light_distance - slack
        visible = coverage * unoccluded
        entry.pixels = float(coverage.sum())
        entry.visible_fraction = float(visible.sum() / max(coverage.sum(), 1e-12))
        if not visible.any():
            entry.reason = "hidden behind geometry"
            continue
        t = float(np.clip(transmittance_to(point[None])[0], 0.0, 1.0))
        entry.transmittance, entry.optical_depth = t, float(-math.log(max(t, 1e-30)))
        entry.irradiance, entry.drawn = irradiance, True
        entry.reason = "drawn" if entry.visible_fraction > 0.999 else "partly hidden: clipped"
        footprints.append(Footprint(light.name, row0, col0,
                                    visible / coverage.sum() * irradiance * t, entry.optical_depth))
    return footprints, report


def emission_footprints(camera: CameraModel, emission: np.ndarray,
                        transmittance: np.ndarray | None = None) -> list[Footprint]:
    """Each connected patch of directly visible emissive surface as one light.

    ``emission`` is the radiance of what the eye sees directly (Cycles' Emit pass);
    radiance x pixel solid angle is the irradiance a pixel's worth sends to the eye, and
    ``transmittance`` (the X map without MinBound) what the medium lets through.
    """
    from scipy import ndimage

    glow = np.asarray(emission, dtype=np.float64)
    glow = luminance(np.moveaxis(glow[..., :3], -1, 0)) if glow.ndim == 3 else glow
    glow = np.maximum(glow, 0.0)
    tau_source = np.ones_like(glow) if transmittance is None else np.asarray(transmittance, dtype=np.float64)
    labels, count = ndimage.label(glow > 0)
    footprints = []
    for index, window in enumerate(ndimage.find_objects(labels), start=1):
        mask = labels[window] == index
        t = tau_source[window]
        values = np.where(mask, glow[window] * t, 0.0) * pixel_solid_angle(camera)
        if values.sum() <= 0:
            continue
        weighted_t = float((glow[window] * t)[mask].sum() / max(glow[window][mask].sum(), 1e-300))
        footprints.append(Footprint(f"emissive surface {index}", window[0].start, window[1].start,
                                    values, float(-math.log(max(weighted_t, 1e-30)))))
    return footprints


#: An emissive patch whose centre lies within this many pixels of a lamp's footprint is the
#: lamp's own bulb or lens (a street lamp's glass, a headlight's disc): one light, not two.
MERGE_DISTANCE_PX = 4.0


def merge_footprints(lamps: list[Footprint], surfaces: list[Footprint],
                     distance_px: float = MERGE_DISTANCE_PX) -> list[Footprint]:
    """Lamps with the emissive surfaces that are their visible bulbs merged into them."""
    merged = [Footprint(f.name, f.row0, f.col0, f.values.copy(), f.optical_depth) for f in lamps]
    rest = []
    for surface in surfaces:
        h, w = surface.values.shape
        rows, cols = np.nonzero(surface.values)
        weights = surface.values[rows, cols]
        centre_row = surface.row0 + float((rows * weights).sum() / weights.sum()) + 0.5
        centre_col = surface.col0 + float((cols * weights).sum() / weights.sum()) + 0.5
        owner = None
        for lamp in merged:
            lh, lw = lamp.values.shape
            if (lamp.row0 - distance_px <= centre_row <= lamp.row0 + lh + distance_px
                    and lamp.col0 - distance_px <= centre_col <= lamp.col0 + lw + distance_px):
                owner = lamp
                break
        if owner is None:
            rest.append(surface)
            continue
        row0, col0 = min(owner.row0, surface.row0), min(owner.col0, surface.col0)
        row1 = max(owner.row0 + owner.values.shape[0], surface.row0 + h)
        col1 = max(owner.col0 + owner.values.shape[1], surface.col0 + w)
        values = np.zeros((row1 - row0, col1 - col0))
        for part in (owner, surface):
            ph, pw = part.values.shape
            values[part.row0 - row0:part.row0 - row0 + ph, part.col0 - col0:part.col0 - col0 + pw] += part.values
        owner.row0, owner.col0, owner.values = row0, col0, values
    return merged + rest


def zero_light_map(camera: CameraModel, lights: list[LightSource], distance: np.ndarray,
                   transmittance_to: Callable[[np.ndarray], np.ndarray],
                   emission: np.ndarray | None = None,
                   emission_transmittance: np.ndarray | None = None,
                   ) -> tuple[np.ndarray, list[DrawnLight]]:
    """L_0 for the camera's full frame: every footprint summed, as the paper draws it.

    Returns the (H, W) float32 map and one DrawnLight per lamp (why it was or was not drawn).
    """
    footprints, report = lamp_footprints(camera, lights, distance, transmittance_to)
    if emission is not None:
        footprints = merge_footprints(footprints, emission_footprints(camera, emission, emission_transmittance))
    out = np.zeros((camera.height, camera.width), dtype=np.float64)
    for footprint in footprints:
        footprint.place(out.shape, out=out)
    return out.astype(np.float32), report


def pixel_solid_angle(camera: CameraModel) -> float:
    """Solid angle of one pixel near the view axis (orthographic cameras: its area), so
    that radiance x this is the irradiance a pixel's worth of emitter sends to the eye."""
    xmin, xmax, ymin, ymax, plane = camera.view_plane()
    area = (xmax - xmin) / camera.width * (ymax - ymin) / camera.height
    return area / (plane * plane) if camera.kind == "PERSP" else area


def _lamp_footprint(camera: CameraModel, light: LightSource):
    point = np.asarray(light.location, dtype=np.float64)
    col, row, depth = camera.project(point[None])
    if not depth[0] > camera.clip_start:
        return None, 0.0, point
    light_distance = float(np.linalg.norm(point - camera.eye))
    if light.kind == "AREA":
        axes = _perpendicular_axes(np.asarray(light.direction))
        return _footprint_polygon(camera, _area_corners(light, axes)), light_distance, point
    radius_px = max(light.size, 0.0) / float(camera.pixel_size_at(depth[0]))
    return _footprint_disc(camera, float(col[0]), float(row[0]), radius_px), light_distance, point


def _sun_footprint(camera: CameraModel, light: LightSource):
    if camera.kind == "ORTHO":
        return None, math.inf, camera.eye
    toward_sun = -np.asarray(light.direction, dtype=np.float64)
    far = camera.eye + toward_sun * camera.clip_end * 0.999
    col, row, depth = camera.project(far[None])
    if not depth[0] > 0:
        return None, math.inf, far
    half_angle = max(0.5 * light.size, 1e-4)
    xmin, xmax, _, _, plane = camera.view_plane()
    radius_px = math.tan(half_angle) * plane / ((xmax - xmin) / camera.width)
    return _footprint_disc(camera, float(col[0]), float(row[0]), radius_px), math.inf, far
