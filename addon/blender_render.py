"""A still rendered as Blender renders it (F12: the file's samples, denoiser, compositor and
its File Output nodes) into one float EXR, with Auto Volumes: ``xsl-render render
SCENE.blend --out FILE.exr`` without ``--mode``. The scene gets every setting back."""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from ..core.files import atomic_path
from . import auto_volumes
from .scene.probe import camera_model, render_size
from .scene.state import preserved_scene


@dataclass(frozen=True)
class BlenderStill:
    """What a still rendered as Blender renders it was."""

    frame: int
    resolution: tuple[int, int]
    samples: int
    seconds: float
    plan: object | None          # Auto Volumes' ShotChoice, None: the file's own settings

    def to_dict(self) -> dict:
        """The --stats JSON of ``xsl-render render`` without --mode."""
        plan = self.plan
        return {"mode": "blender", "frame": self.frame, "resolution": list(self.resolution),
                "samples": self.samples, "wall_s": self.seconds,
                "auto_volumes": None if plan is None else {
                    "described": plan.describe(), "shot": list(plan.shot), "frames": list(plan.frames),
                    "estimator": plan.choice.to_dict()}}

    def describe(self) -> str:
        choice = "the file's own volume settings" if self.plan is None else f"Auto Volumes: {self.plan.describe()}"
        width, height = self.resolution
        return f"frame {self.frame}, {width}x{height}, {self.samples} spp as the file sets, {self.seconds:.2f} s; {choice}"


def render_still(scene, out: str | Path, auto: bool = True) -> BlenderStill:
    """Render ``scene`` at its current frame as F12 does into ``out`` (an OpenEXR of the
    composited image, RGBA float), with Auto Volumes where ``auto``."""
    import bpy

    camera_model(scene)                          # InputError for a scene without a camera
    size = render_size(scene)
    auto_volumes.last_plans.pop(scene.as_pointer(), None)
    with preserved_scene(scene), atomic_path(out) as temporary, auto_volumes.forced(scene, auto):
        render = scene.render
        settings = render.image_settings
        if hasattr(settings, "media_type"):      # Blender 5.0+: the format follows the media type
            settings.media_type = "IMAGE"
        settings.file_format, settings.color_mode, settings.color_depth = "OPEN_EXR", "RGBA", "32"
        render.use_file_extension = False
        render.filepath = str(temporary)
        started = time.perf_counter()
        result = bpy.ops.render.render(write_still=True, scene=scene.name)
        seconds = time.perf_counter() - started
        if "FINISHED" not in result or not Path(temporary).is_file():
            raise RuntimeError(f"Blender did not write the render ({result})")
    return BlenderStill(scene.frame_current, size, int(scene.cycles.samples), seconds,
                        auto_volumes.last_plans.get(scene.as_pointer()) if auto else None)
