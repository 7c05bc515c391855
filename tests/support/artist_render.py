"""The artist's own F12 on a scene, with persistent data on: what their next render after one
of our runs gives (our settings must not survive in Cycles' session)."""
from __future__ import annotations

from pathlib import Path


def artists_f12(blender, scene, folder: Path, samples: int = 2, seed: int = 0):
    """Set the scene up for the artist's renders (persistent data, ``samples``, ``seed``, no
    denoiser, EXR into ``folder``) and return a function rendering it as F12 does, returning
    the image. Nothing may be assigned between two calls in a test: assigning any scene
    property, even its own value, tags the scene, which would hide what the tests look for."""
    from xsl_render.core.imageio import read_image

    scene.render.use_persistent_data = True
    scene.cycles.samples, scene.cycles.seed, scene.cycles.use_denoising = samples, seed, False
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.filepath = str(folder / "f12")

    def render():
        blender.ops.render.render(write_still=True, scene=scene.name)
        return read_image(folder / "f12.exr")

    return render
