"""Cycles' volume-stack rules as the X map applies them (``core.maps.volume_stack``); the
renders that show Cycles behaving so are in ``test_xmap_coincident.py``."""
from __future__ import annotations

import numpy as np
import pytest

from xsl_render.core.camera import CameraModel
from xsl_render.core.maps.volume_stack import (ENTERING, LEAVING, SURFACE, camera_may_be_inside,
                                               coincident_events, near_plane_bounds, probe_inside,
                                               surface_exit_ties)


def _camera(kind="PERSP", location=(0.0, 0.0, 0.0), clip_start=0.1, **kwargs):
    matrix = np.eye(4)
    matrix[:3, 3] = location                  # looking down -Z
    return CameraModel(kind=kind, matrix_world=matrix, width=64, height=36, lens=36.0,
                       sensor_width=36.0, clip_start=clip_start, **kwargs)


def test_near_plane_box_is_the_clip_start_rectangle_grown_by_the_clip_start():
    lo, hi = near_plane_bounds(_camera(clip_start=2.0))
    # lens = sensor width: the frame is 1 wide at distance 1, 2 wide at the clip start.
    assert lo == pytest.approx([-1.0 - 2.0, -36 / 64 - 2.0, -2.0 - 2.0])
    assert hi == pytest.approx([1.0 + 2.0, 36 / 64 + 2.0, -2.0 + 2.0])
    lo, hi = near_plane_bounds(_camera("ORTHO", clip_start=0.5, ortho_scale=4.0, shift_x=0.25))
    assert lo == pytest.approx([-2.0 + 1.0 - 0.5, -36 / 32 - 0.5, -1.0])
    assert hi == pytest.approx([2.0 + 1.0 + 0.5, 36 / 32 + 0.5, 0.0])


def test_gate_needs_an_object_box_overlapping_the_near_plane_box():
    camera = _camera(location=(0.0, 0.0, -1.0))          # near plane box z in [-1.2, -1.0]
    plane_above = (np.array([-30.0, -30.0, 0.0]), np.array([30.0, 30.0, 0.0]))
    box_around = (np.array([-5.0, -5.0, -5.0]), np.array([5.0, 5.0, 0.0]))
    far_box = (np.array([10.0, 10.0, -2.0]), np.array([12.0, 12.0, 0.0]))
    assert not camera_may_be_inside(camera, [plane_above, far_box])
    assert camera_may_be_inside(camera, [plane_above, box_around])
    assert not camera_may_be_inside(camera, [])


def test_probe_takes_the_first_deciding_face_of_each_ray():
    # ray 0: back face with volume first -> inside
    # ray 1: front face first (entered another part) -> outside, whatever follows
    # ray 2: a surface-only face from behind is passed over; then a volume back face
    # ray 3: only a surface-only back face -> outside
    # ray 4: no hit -> outside
    ray = np.array([0, 0, 1, 1, 2, 2, 3])
    t = np.array([1.0, 3.0, 0.5, 2.0, 0.2, 0.9, 1.0])
    front = np.array([False, True, True, False, False, False, False])
    has_volume = np.array([True, True, True, True, False, True, False])
    inside = probe_inside(5, ray, t, front, has_volume)
    assert inside.tolist() == [True, False, True, False, False]
    # The order of the hits given does not matter, their distance does.
    shuffled = np.array([6, 3, 1, 5, 0, 2, 4])
    again = probe_inside(5, ray[shuffled], t[shuffled], front[shuffled], has_volume[shuffled])
    assert again.tolist() == inside.tolist()


def test_coincident_events_need_two_owners_at_one_distance():
    ray = np.array([0, 0, 1, 1, 2, 2, 3, 3])
    t = np.array([5.0, 5.0 + 2e-6, 4.0, 4.0 + 1e-6, 7.0, 7.5, 3.0, 3.0 + 1e-7])
    owner = np.array([-1, 0, 2, 2, -1, 0, 1, 0])
    ties = coincident_events(5, ray, t, owner)
    # 0: surface and a volume face 2e-6 apart; 1: one object's two faces (an edge);
    # 2: 0.5 apart; 3: two volumes' faces; 4: no events.
    assert ties.tolist() == [True, False, False, True, False]
    assert not coincident_events(5, ray, t, owner, tolerance=1e-8)[0]


def test_surface_exit_ties_are_the_first_surface_with_a_face_left_there():
    # 0: enters volume 0, leaves it on the floor (the fog box on the ground, seen through it)
    # 1: leaves volume 1 on the floor, seen from inside
    # 2: enters volume 0 on the surface (a water plane on the box's top): another tie
    # 3: leaves volume 0 on the floor while entering volume 1 there: three events at once
    # 4: two volumes' faces meet, the surface is elsewhere
    # 5: leaves volume 0 on a surface that is volume 1's face (glass over water)
    # 6: no tie at all
    ray = np.array([0, 0, 0, 1, 1, 2, 2, 3, 3, 3, 4, 4, 4, 5, 5, 6, 6])
    t = np.array([1.0, 5.0, 5.0 + 1e-6, 4.0, 4.0, 3.0, 3.0, 6.0, 6.0, 6.0, 2.0, 2.0, 9.0,
                  7.0, 7.0, 1.0, 8.0])
    owner = np.array([0, 0, -1, 1, -1, 0, -1, 0, 1, -1, 0, 1, -1, 0, 1, 0, -1])
    kind = np.array([ENTERING, LEAVING, SURFACE, LEAVING, SURFACE, ENTERING, SURFACE, LEAVING,
                     ENTERING, SURFACE, LEAVING, ENTERING, SURFACE, LEAVING, SURFACE, ENTERING,
                     SURFACE])
    medium = surface_exit_ties(7, ray, t, owner, kind)
    assert medium.tolist() == [0, 1, -1, -1, -1, -1, -1]
    ties = coincident_events(7, ray, t, owner)
    assert ties.tolist() == [True, True, True, True, True, True, False]
    shuffled = np.random.default_rng(0).permutation(len(ray))
    again = surface_exit_ties(7, ray[shuffled], t[shuffled], owner[shuffled], kind[shuffled])
    assert again.tolist() == medium.tolist()
