"""The pinhole and orthographic camera of Blender as plain numpy: rays and projections.

The formulas follow Blender's ``BKE_camera_params_compute_viewplane``: the sensor is fitted
to the wider side (or the one ``sensor_fit`` names), shift is measured in units of that
side, and pixel (i, j) is the square [i, i+1] x [j, j+1] of the view plane.

Image convention everywhere in xsl_render: arrays are ``[row, column]`` with row 0 at the
*top* of the image (as OpenImageIO reads and writes them); Blender counts pixel rows from
the bottom, so row r is Blender's y = height - 1 - r.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import InputError


#: A world matrix whose 3x3 part has a singular value this small against its largest maps
#: the view to a plane or a line (a camera scaled to zero on an axis): no rays to cast.
MIN_SCALE_RATIO = 1e-9
#: Past this a transform's number is as good as infinite: Cycles computes in 32-bit floats,
#: whose squares overflow beyond 1.8e19 (and Blender stores a typed "inf" as 3.4e38).
MAX_TRANSFORM_VALUE = 1e19


def check_camera_matrix(matrix, name: str = "Camera") -> None:
    """InputError unless ``matrix`` (the camera's 4x4 world matrix) places a camera: finite
    and within :data:`MAX_TRANSFORM_VALUE` (a NaN or infinite location, rotation or scale
    renders nothing meaningful: a black frame with exit code 0) and invertible (a camera
    scaled to zero has no rays; numpy would fail deep inside with LinAlgError)."""
    matrix = np.asarray(matrix, dtype=np.float64)
    if (matrix.shape != (4, 4) or not np.isfinite(matrix).all()
            or np.abs(matrix).max() > MAX_TRANSFORM_VALUE):
        raise InputError(f"camera '{name}' has a transform with NaN or infinite numbers "
                         f"(location, rotation or scale; at most {MAX_TRANSFORM_VALUE:g})")
    singular = np.linalg.svd(matrix[:3, :3], compute_uv=False)
    if singular[0] == 0.0 or singular[-1] <= MIN_SCALE_RATIO * singular[0]:
        raise InputError(f"camera '{name}' is scaled to zero (its transform is singular): "
                         "give it a scale other than 0 on every axis")


@dataclass(frozen=True)
class CameraModel:
    """Everything needed to cast the camera's rays, in plain numbers.

    ``matrix_world`` is the camera object's 4x4 world matrix (Blender cameras look down
    their local -Z with +Y up). Lengths are in scene units, ``lens`` and the sensor in mm.
    """

    kind: str                      # "PERSP" or "ORTHO"
    matrix_world: np.ndarray       # (4, 4)
    width: int                     # render resolution in pixels (after the percentage)
    height: int
    lens: float = 50.0
    sensor_width: float = 36.0
    sensor_height: float = 24.0
    sensor_fit: str = "AUTO"       # AUTO, HORIZONTAL, VERTICAL
    ortho_scale: float = 7.0
    shift_x: float = 0.0
    shift_y: float = 0.0
    clip_start: float = 0.1
    clip_end: float = 1000.0
    pixel_aspect_x: float = 1.0
    pixel_aspect_y: float = 1.0
    # Render border as fractions (min_x, min_y, max_x, max_y), Blender's bottom-up y.
    border: tuple[float, float, float, float] | None = None
    name: str = field(default="Camera", compare=False)

    def __post_init__(self) -> None:
        if self.kind not in ("PERSP", "ORTHO"):
            kind = {"PANO": "panoramic"}.get(self.kind, self.kind.lower())
            raise InputError(f"camera '{self.name}' is {kind}; xsl_render needs a "
                             "perspective or orthographic camera")
        if self.width < 1 or self.height < 1:
            raise InputError(f"render resolution {self.width}x{self.height} has no pixels")
        if not self.clip_start < self.clip_end:
            raise InputError(f"camera '{self.name}' has clip start {self.clip_start:g} >= "
                             f"clip end {self.clip_end:g}")
        if self.clip_start < 0:
            raise InputError(f"camera '{self.name}' has a negative clip start")
        if self.kind == "PERSP" and self.lens <= 0:
            raise InputError(f"camera '{self.name}' has focal length {self.lens:g} <= 0")
        if self.kind == "ORTHO" and self.ortho_scale <= 0:
            raise InputError(f"camera '{self.name}' has orthographic scale {self.ortho_scale:g} <= 0")
        check_camera_matrix(self.matrix_world, self.name)

    # --- the view plane -------------------------------------------------------------
    def _fit(self) -> str:
        if self.sensor_fit != "AUTO":
            return self.sensor_fit
        wide = self.pixel_aspect_x * self.width >= self.pixel_aspect_y * self.height
        return "HORIZONTAL" if wide else "VERTICAL"

    def view_plane(self) -> tuple[float, float, float, float, float]:
        """(xmin, xmax, ymin, ymax, plane_distance) of the view plane in camera space.

        For a perspective camera the plane lies at distance 1 in front of the eye
        (Blender uses clip_start; the rays are the same); for an orthographic one the
        extents are in scene units and the distance is unused (0).
        """
        fit = self._fit()
        # Blender measures AUTO and HORIZONTAL fits with the sensor width, even when AUTO
        # ends up fitting the height of a portrait frame.
        sensor = self.sensor_height if self.sensor_fit == "VERTICAL" else self.sensor_width
        ycor = self.pixel_aspect_y / self.pixel_aspect_x
        viewfac = self.width if fit == "HORIZONTAL" else ycor * self.height
        if self.kind == "PERSP":
            pixsize, distance = sensor / self.lens, 1.0
        else:
            pixsize, distance = self.ortho_scale, 0.0
        pixsize /= viewfac
        xmin = (-0.5 * self.width + self.shift_x * viewfac) * pixsize
        xmax = (0.5 * self.width + self.shift_x * viewfac) * pixsize
        ymin = (-0.5 * ycor * self.height + self.shift_y * viewfac) * pixsize
        ymax = (0.5 * ycor * self.height + self.shift_y * viewfac) * pixsize
        return xmin, xmax, ymin, ymax, distance

    # --- rays -----------------------------------------------------------------------
    def pixel_window(self) -> tuple[int, int, int, int]:
        """(row0, row1, col0, col1) of the pixels to compute: the render border, or all.

        Rows count from the top; the window is half-open. Blender turns the border's
        fractions into pixels by truncating ``border * size`` computed in single
        precision, which is what this reproduces (checked against Cycles renders).
        """
        if self.border is None:
            return 0, self.height, 0, self.width
        bx0, by0, bx1, by1 = (np.float32(v) for v in self.border)
        col0, col1 = int(bx0 * np.float32(self.width)), int(bx1 * np.float32(self.width))
        y0, y1 = int(by0 * np.float32(self.height)), int(by1 * np.float32(self.height))
        if col1 <= col0 or y1 <= y0:
            raise InputError(f"the render border of camera '{self.name}' has zero area")
        return self.height - y1, self.height - y0, col0, col1

    def pixel_rays(self, window: tuple[int, int, int, int] | None = None,
                   ) -> tuple[np.ndarray, np.ndarray]:
        """World-space ray origins and unit directions through pixel centres.

        Returns two float64 arrays of shape (rows, cols, 3) for ``window`` (default: the
        whole frame). Origins of perspective rays are the eye; orthographic rays start on
        the plane through the eye, and in both cases the first ``clip_start`` of each ray
        is not visible (see ``clip_range``).
        """
        row0, row1, col0, col1 = window or (0, self.height, 0, self.width)
        xmin, xmax, ymin, ymax, distance = self.view_plane()
        cols = np.arange(col0, col1) + 0.5
        ys = (self.height - (np.arange(row0, row1) + 0.5))          # Blender's bottom-up y
        x = xmin + cols * (xmax - xmin) / self.width
        y = ymin + ys * (ymax - ymin) / self.height
        xx, yy = np.meshgrid(x, y)
        rotation = np.asarray(self.matrix_world, dtype=np.float64)[:3, :3]
        # Blender camera matrices may carry scale; directions use the normalised axes.
        axes = rotation / np.linalg.norm(rotation, axis=0, keepdims=True)
        eye = np.asarray(self.matrix_world, dtype=np.float64)[:3, 3]
        if self.kind == "PERSP":
            local = np.stack([xx, yy, -np.full_like(xx, distance)], axis=-1)
            directions = local @ axes.T
            directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
            origins = np.broadcast_to(eye, directions.shape).copy()
        else:
            local = np.stack([xx, yy, np.zeros_like(xx)], axis=-1)
            origins = eye + local @ axes.T
            directions = np.broadcast_to(-axes[:, 2], origins.shape).copy()
        return origins, directions

    def clip_range(self, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distances along each ray where it enters and leaves the clipping range.

        Blender clips by planar depth (distance along the view axis), so along a
        perspective ray the limits grow by 1 / cos(angle to the axis).
        """
        if self.kind == "ORTHO":
            shape = directions.shape[:-1]
            return np.full(shape, self.clip_start), np.full(shape, self.clip_end)
        axis = self.view_axis()
        cos = directions @ axis
        return self.clip_start / cos, self.clip_end / cos

    def view_axis(self) -> np.ndarray:
        """Unit vector the camera looks along (its local -Z) in world space."""
        z = np.asarray(self.matrix_world, dtype=np.float64)[:3, 2]
        return -z / np.linalg.norm(z)

    @property
    def eye(self) -> np.ndarray:
        return np.asarray(self.matrix_world, dtype=np.float64)[:3, 3].copy()

    # --- projection -----------------------------------------------------------------
    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Project world points to continuous pixel coordinates.

        Returns (col, row, depth): ``col`` and ``row`` in pixels from the left and top edges
        (pixel centres at .5), ``depth`` the planar distance in front of the camera
        (<= 0 means behind it). Works on any (..., 3) array.
        """
        points = np.asarray(points, dtype=np.float64)
        inverse = np.linalg.inv(np.asarray(self.matrix_world, dtype=np.float64))
        local = points @ inverse[:3, :3].T + inverse[:3, 3]
        depth = -local[..., 2]
        xmin, xmax, ymin, ymax, distance = self.view_plane()
        if self.kind == "PERSP":
            with np.errstate(divide="ignore", invalid="ignore"):
                x = local[..., 0] / np.where(depth > 0, depth, np.nan) * distance
                y = local[..., 1] / np.where(depth > 0, depth, np.nan) * distance
        else:
            x, y = local[..., 0], local[..., 1]
        col = (x - xmin) / (xmax - xmin) * self.width
        row = self.height - (y - ymin) / (ymax - ymin) * self.height
        return col, row, depth

    def pixel_size_at(self, depth: np.ndarray | float) -> np.ndarray | float:
        """Width of one pixel in scene units at planar ``depth`` (for projecting sizes)."""
        xmin, xmax, _, _, distance = self.view_plane()
        per_pixel = (xmax - xmin) / self.width
        if self.kind == "PERSP":
            return per_pixel * np.asarray(depth, dtype=np.float64) / distance
        return per_pixel + 0.0 * np.asarray(depth, dtype=np.float64)

    def in_frame(self, points: np.ndarray, margin_px: np.ndarray | float = 0.0) -> np.ndarray:
        """True where a world point (padded by ``margin_px`` pixels) shows in the frame."""
        col, row, depth = self.project(points)
        margin = np.asarray(margin_px, dtype=np.float64)
        with np.errstate(invalid="ignore"):
            inside = ((col >= -margin) & (col <= self.width + margin)
                      & (row >= -margin) & (row <= self.height + margin))
            return inside & (depth > self.clip_start) & (depth < self.clip_end)


def border_for_window(window: tuple[int, int, int, int], width: int, height: int,
                      ) -> tuple[float, float, float, float]:
    """Blender's render border (min_x, min_y, max_x, max_y) that renders exactly ``window``.

    ``window`` is (row0, row1, col0, col1), rows from the top, half-open. Blender and Cycles
    turn border fractions into pixels by truncation and ``pixel_window`` above by rounding;
    a fraction 0.3 px past each pixel edge gives the same pixel both ways (and survives
    float32), and the frame's far edge is exactly 1.
    """
    row0, row1, col0, col1 = window
    if not (0 <= row0 < row1 <= height and 0 <= col0 < col1 <= width):
        raise ValueError(f"window {window} lies outside the {width}x{height} frame")

    def fraction(pixel: int, size: int) -> float:
        return 1.0 if pixel >= size else (pixel + 0.3) / size

    # Blender's y counts up from the bottom: rows [row0, row1) are y in [height-row1, height-row0).
    return (fraction(col0, width), fraction(height - row1, height),
            fraction(col1, width), fraction(height - row0, height))
