"""CameraModel: hand-computed rays and projections, then agreement with Blender itself."""
from __future__ import annotations

import math

import numpy as np
import pytest

from xsl_render.core.camera import CameraModel
from xsl_render.core.errors import InputError


def looking_down_minus_z(**kwargs) -> CameraModel:
    return CameraModel(kind=kwargs.pop("kind", "PERSP"), matrix_world=np.eye(4),
                       width=kwargs.pop("width", 4), height=kwargs.pop("height", 2), **kwargs)


def test_centre_ray_of_a_symmetric_frame_is_the_view_axis():
    cam = looking_down_minus_z(width=3, height=3)
    origins, directions = cam.pixel_rays()
    assert directions.shape == (3, 3, 3)
    np.testing.assert_allclose(directions[1, 1], [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(origins, 0.0)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=-1), 1.0)


def test_corner_ray_by_hand():
    # 36 mm sensor, 50 mm lens, 4x2 pixels: the view plane at distance 1 spans x in
    # [-0.36, 0.36], y in [-0.18, 0.18]; the top-left pixel centre is (-0.27, 0.09).
    cam = looking_down_minus_z(lens=50.0, sensor_width=36.0)
    _, directions = cam.pixel_rays()
    expected = np.array([-0.27, 0.09, -1.0])
    np.testing.assert_allclose(directions[0, 0], expected / np.linalg.norm(expected), atol=1e-12)


def test_shift_moves_the_frame_by_the_fitted_side():
    cam = looking_down_minus_z(shift_x=0.5)
    xmin, xmax, *_ = cam.view_plane()
    assert xmin == pytest.approx(0.0) and xmax == pytest.approx(0.72)


def test_orthographic_rays_are_parallel_and_spread_over_ortho_scale():
    cam = looking_down_minus_z(kind="ORTHO", ortho_scale=4.0)
    origins, directions = cam.pixel_rays()
    np.testing.assert_allclose(directions, np.broadcast_to([0, 0, -1], directions.shape))
    np.testing.assert_allclose(origins[0, :, 0], [-1.5, -0.5, 0.5, 1.5])
    np.testing.assert_allclose(origins[:, 0, 1], [0.5, -0.5])


@pytest.mark.parametrize("kind", ["PERSP", "ORTHO"])
def test_projecting_a_pixel_ray_lands_on_its_pixel_centre(kind):
    cam = CameraModel(kind=kind, matrix_world=np.array([[1, 0, 0, 1], [0, 0, -1, -5],
                                                         [0, 1, 0, 2], [0, 0, 0, 1]], float),
                      width=7, height=5, shift_x=0.1, shift_y=-0.05)
    origins, directions = cam.pixel_rays()
    points = origins + 3.7 * directions
    col, row, depth = cam.project(points)
    cols, rows = np.meshgrid(np.arange(7) + 0.5, np.arange(5) + 0.5)
    np.testing.assert_allclose(col, cols, atol=1e-9)
    np.testing.assert_allclose(row, rows, atol=1e-9)
    assert (depth > 0).all()


def test_render_border_window_counts_rows_from_the_top():
    cam = looking_down_minus_z(width=10, height=10, border=(0.2, 0.0, 0.5, 0.3))
    assert cam.pixel_window() == (7, 10, 2, 5)


@pytest.mark.parametrize("changes, message", [
    ({"kind": "PANO"}, "panoramic"),
    ({"clip_start": 5.0, "clip_end": 1.0}, "clip start"),
    ({"width": 0}, "no pixels"),
    ({"border": (0.5, 0.5, 0.5, 0.9)}, "zero area"),
])
def test_bad_cameras_are_input_errors(changes, message):
    with pytest.raises(InputError, match=message):
        looking_down_minus_z(**changes).pixel_window()


@pytest.mark.blender
@pytest.mark.parametrize("kind, fit, size, shift", [
    ("PERSP", "AUTO", (64, 36), (0.0, 0.0)),
    ("PERSP", "AUTO", (30, 50), (0.1, -0.2)),
    ("PERSP", "VERTICAL", (64, 36), (0.0, 0.15)),
    ("ORTHO", "HORIZONTAL", (40, 40), (0.2, 0.0)),
])
def test_projection_matches_blender(blender, kind, fit, size, shift):
    """world_to_camera_view is Blender's own projection; ours must agree with it."""
    import mathutils
    from bpy_extras.object_utils import world_to_camera_view

    from xsl_render.addon.scene.probe import camera_model

    bpy = blender
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = size
    data = bpy.data.cameras.new("cam")
    data.type, data.sensor_fit, data.lens, data.ortho_scale = kind, fit, 35.0, 9.0
    data.shift_x, data.shift_y = shift
    ob = bpy.data.objects.new("cam", data)
    scene.collection.objects.link(ob)
    scene.camera = ob
    ob.location = (1.0, -6.0, 2.5)
    ob.rotation_euler = (math.radians(75), math.radians(5), math.radians(20))
    bpy.context.view_layer.update()
    cam = camera_model(scene)
    rng = np.random.default_rng(3)
    points = rng.uniform(-3, 3, size=(50, 3)) + np.array([3.0, 3.0, 1.0])
    col, row, depth = cam.project(points)
    for p, c, r, d in zip(points, col, row, depth):
        ndc = world_to_camera_view(scene, ob, mathutils.Vector(p))
        assert c == pytest.approx(ndc.x * size[0], abs=1e-4)
        assert r == pytest.approx((1.0 - ndc.y) * size[1], abs=1e-4)
        assert d == pytest.approx(ndc.z, abs=1e-6)


@pytest.mark.parametrize("matrix, words", [
    (np.diag([0.0, 0.0, 0.0, 1.0]), "scaled to zero"),
    (np.diag([1.0, 0.0, 1.0, 1.0]), "scaled to zero"),
    (np.array([[1, 2, 0, 0], [2, 4, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], float), "scaled to zero"),
    (np.where(np.eye(4) > 0, 1.0, np.nan), "NaN or infinite"),
    (np.array([[1, 0, 0, np.inf], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]), "NaN or infinite"),
    (np.array([[1, 0, 0, 3.4e38], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]), "NaN or infinite"),
])
def test_a_camera_that_places_nothing_is_refused(matrix, words):
    """Issue 23: a zero scale gave LinAlgError deep inside, a NaN location a black render."""
    with pytest.raises(InputError, match=words):
        CameraModel(kind="PERSP", matrix_world=matrix, width=8, height=6, name="Cam")


@pytest.mark.parametrize("matrix", [np.diag([-1.0, 1.0, 1.0, 1.0]), np.diag([1e-3, 1e-3, 1e-3, 1.0]),
                                    np.diag([1e3, 1.0, 1.0, 1.0])])
def test_mirrored_small_and_stretched_cameras_are_cameras(matrix):
    origins, directions = CameraModel(kind="PERSP", matrix_world=matrix, width=8, height=6).pixel_rays()
    assert np.isfinite(origins).all() and np.isfinite(directions).all()
