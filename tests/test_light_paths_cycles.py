"""The light-path prediction against what Cycles renders, and auto's guard.

A dense, self-shadowing noise cloud lit by a sun and a sky over a floor: Cycles ray-marches
it at a coarse and a fine step rate, and the difference between the two renders (its light
through the cloud, the cloud's shadow on the floor) is what the prediction must follow,
pixel by pixel, as ``test_ray_marching`` checks the camera's transmittance.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
W, H = 96, 54


def sunlit_cloud(bpy, density=30.0, sky=0.3):
    """A cloud of noise-textured density up to ``density`` (optical depth ~40 across), albedo
    0.95, over a floor, lit by a sun and a constant sky; the camera sees it whole."""
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = W, H
    scene.render.resolution_percentage = 100
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    camera.location, camera.rotation_euler = (0.0, -9.0, 2.5), (math.radians(82), 0.0, 0.0)
    bpy.ops.mesh.primitive_plane_add(size=40, location=(0, 5, 0))
    bpy.ops.mesh.primitive_uv_sphere_add(radius=2.0, segments=32, ring_count=16, location=(0, 3, 3.0))
    cloud = bpy.context.active_object
    material = bpy.data.materials.new("Cloud")
    cloud.data.materials.append(material)
    tree = material.node_tree
    tree.nodes.clear()
    output, volume = tree.nodes.new("ShaderNodeOutputMaterial"), tree.nodes.new("ShaderNodeVolumePrincipled")
    volume.inputs["Color"].default_value = (0.95, 0.95, 0.95, 1.0)
    coords, noise, ramp = (tree.nodes.new(t) for t in ("ShaderNodeTexCoord", "ShaderNodeTexNoise", "ShaderNodeMapRange"))
    noise.inputs["Scale"].default_value, noise.inputs["Detail"].default_value = 2.0, 4.0
    ramp.inputs["From Min"].default_value, ramp.inputs["From Max"].default_value = 0.4, 0.7
    ramp.inputs["To Max"].default_value = density
    tree.links.new(coords.outputs["Object"], noise.inputs["Vector"])
    tree.links.new(noise.outputs["Fac"], ramp.inputs["Value"])
    tree.links.new(ramp.outputs["Result"], volume.inputs["Density"])
    tree.links.new(volume.outputs[0], output.inputs["Volume"])
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy, sun.rotation_euler = 3.0, (math.radians(40), math.radians(20), 0.0)
    scene.collection.objects.link(sun)
    scene.world = bpy.data.worlds.new("Sky")
    background = scene.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (0.4, 0.6, 1.0, 1.0)
    background.inputs["Strength"].default_value = sky
    return scene


def marched_render(bpy, scene, rate: float, samples: int) -> np.ndarray:
    """Cycles' render of ``scene`` ray-marched at ``rate``, not denoised: (H, W) luminance."""
    from xsl_render.addon.cycles.render import render_passes
    from xsl_render.addon.scene.state import preserved_scene

    with preserved_scene(scene):
        cycles = scene.cycles
        cycles.samples, cycles.use_adaptive_sampling, cycles.use_denoising = samples, False, False
        cycles.volume_biased, cycles.volume_step_rate = True, rate
        return render_passes(scene)["Combined"][..., :3] @ LUMINANCE


def full_frame_prediction(bpy, scene, stride: int = 2):
    """The light-path prediction on every ``stride``-th pixel of the frame (row, col)."""
    import xsl_render.addon.maps.light_paths as light_paths
    from xsl_render.addon.maps.zbuffer import cast_camera_rays
    from xsl_render.addon.scene.geometry import scan_scene
    from xsl_render.addon.scene.probe import camera_model
    from xsl_render.core.maps.transmittance import medium_segments

    depsgraph = bpy.context.evaluated_depsgraph_get()
    geometry, media = scan_scene(scene, depsgraph)
    rays = cast_camera_rays(camera_model(scene, size=(W, H)), geometry)
    rows, cols = np.mgrid[0:H:stride, 0:W:stride]
    pixels = (rows * W + cols).ravel()
    emitters, why = light_paths.scene_emitters(scene, depsgraph, np.zeros(3))
    assert why is None
    saved = light_paths.LIGHT_RAYS
    light_paths.LIGHT_RAYS = len(pixels)
    try:
        predictor = light_paths.light_path_predictor(scene, depsgraph, rays, geometry, media,
                                                     [medium_segments(rays, m) for m in media],
                                                     pixels, emitters, (4.0, 2.0, 1.0, 0.5, 0.25))
    finally:
        light_paths.LIGHT_RAYS = saved
    # The predictor keeps the pixels its light can change, in the order of ``pixels``.
    directions = rays.directions.reshape(-1, 3)
    kept = np.array([int(np.argmin(((directions[pixels] - d) ** 2).sum(axis=1))) for d in predictor.directions])
    return predictor, pixels[kept]


@pytest.mark.blender
@pytest.mark.render
def test_predicted_picture_error_follows_cycles_on_a_sunlit_cloud(blender):
    """Cycles at step rates 4 and 0.25 (512 spp, no denoising, 3x3 box): where the light
    through the cloud and its shadow change, the predicted change follows it."""
    from scipy.ndimage import uniform_filter

    scene = sunlit_cloud(blender)
    predictor, pixels = full_frame_prediction(blender, scene)
    coarse = uniform_filter(marched_render(blender, scene, 4.0, 512), 3).ravel()[pixels]
    fine = uniform_filter(marched_render(blender, scene, 0.25, 512), 3).ravel()[pixels]
    measured = coarse - fine
    predicted = predictor.error(4.0).error - predictor.error(0.25).error
    assert np.abs(measured).mean() > 0.005                    # a change worth predicting
    assert np.corrcoef(measured, predicted)[0, 1] > 0.7
    assert 0.6 < np.abs(predicted).sum() / np.abs(measured).sum() < 1.5
    # The cloud's brightness as a whole moves as Cycles' does.
    assert 0.5 < predicted.sum() / measured.sum() < 2.0


@pytest.mark.blender
def test_auto_keeps_null_scattering_for_a_dense_sunlit_cloud_that_marching_brightens(blender):
    """The issue's cloud: the camera ray's transmittance hides ray marching's bias (near 0
    through the cloud) but the shadow rays' does not; no rate passes at 64 spp."""
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.core.sampling.render_options import RenderOptions

    scene = sunlit_cloud(blender)
    choice = choose_estimator(scene, RenderOptions(max_spp=64, estimator="auto"), 64)
    assert choice.biased is False
    assert choice.tried[2.0] > 0.1                            # rate 2: far too bright
