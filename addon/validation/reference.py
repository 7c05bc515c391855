"""The converged reference of a scene: looked up in the caches, or rendered and cached.

The render is ``render_uniform`` with the reference's samples and seed, denoised as every run
is; its key, defaults and cache folders are ``core.validation.reference``'s. It takes minutes:
progress is reported sample by sample, and Ctrl-C follows the command line's convention (the
first asks to stop after the render, which then writes nothing; the second stops at once).
The cache never holds half an entry. Several frames render one after another in one Cycles
session, each cached as it is done, so a scene whose volumes stand still builds its octree once."""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

from ...core.files import file_sha256
from ...core.progress import ProgressCallback, WeightedSteps
from ...core.sampling.render_options import RenderOptions
from ...core.validation.reference import (REFERENCE_SEED, CachedReference, ReferenceInputs, ReferenceRun,
                                          check_reference_options, default_reference_spp,
                                          find_reference, user_folder, write_reference)
from ...core.validation.store import check_output_folder
from ..cycles.denoise import DENOISE_VERSION
from ..cycles.selective_render import render_uniform
from ..scene.probe import render_size
from ..scene.state import preserved_scene


def blender_version() -> str:
    import bpy

    return bpy.app.version_string


def scene_ceiling(scene) -> int:
    """The scene's own Cycles sample count: the contestants' ceiling when none is given."""
    return max(1, int(scene.cycles.samples))


def reference_inputs(scene, blend_path: str | Path, spp: int | None = None, seed: int = REFERENCE_SEED,
                     resolution: tuple[int, int] | None = None, frame: int | None = None,
                     max_spp: int | None = None, blend_sha256: str | None = None) -> ReferenceInputs:
    """The inputs (and so the cache key) of the reference of ``scene`` from ``blend_path``.

    Parameters
    ----------
    spp
        Samples per pixel; None: ``max(1024, 16 x ceiling)``, the ceiling being ``max_spp``
        or the scene's own Cycles sample count.
    seed
        Cycles' seed (default ``REFERENCE_SEED``).
    resolution, frame
        None: the scene's own render size and current frame.
    blend_sha256
        The file's hash when the caller has it already.
    """
    check_reference_options(spp, seed)
    if spp is None:
        spp = default_reference_spp(max_spp if max_spp is not None else scene_ceiling(scene))
    RenderOptions(max_spp=spp, seed=seed, resolution=resolution).check()
    return ReferenceInputs(
        blend_sha256=blend_sha256 or file_sha256(blend_path), scene=scene.name,
        frame=int(scene.frame_current if frame is None else frame),
        resolution=tuple(resolution) if resolution is not None else render_size(scene),
        spp=int(spp), seed=int(seed), blender=blender_version(), denoise=DENOISE_VERSION)


@dataclass(frozen=True)
class Reference:
    """A reference ready to compare with: its file, inputs and where it came from."""

    path: Path
    inputs: ReferenceInputs
    source: str             # "shipped", "cache" or "rendered"
    run: ReferenceRun

    def to_dict(self) -> dict:
        return {"path": str(self.path), "key": self.inputs.key, "source": self.source,
                "inputs": self.inputs.to_dict(), "render_s": self.run.seconds}


def ensure_reference(scene, inputs: ReferenceInputs, progress: ProgressCallback | None = None,
                     environ=None, file_name: str | None = None) -> Reference:
    """The cached reference for ``inputs``, or render it now and cache it.

    ``scene`` must be the scene ``inputs`` were made from (``reference_inputs``); it is left
    as it was found. The user cache folder is checked for writing before the render starts.
    """
    found = find_reference(inputs.key, environ)
    if found is not None:
        return _from_cache(found, inputs)
    folder = check_output_folder(user_folder(environ), "the reference cache")
    image, run = render_reference(scene, inputs, progress)
    entry = write_reference(folder, inputs, image, run, file_name=file_name)
    return Reference(entry.path, inputs, "rendered", run)


def ensure_references(scene, inputs: Sequence[ReferenceInputs], progress: ProgressCallback | None = None,
                       environ=None, file_name: str | None = None,
                       on_frame: Callable[[Reference], object] | None = None) -> list[Reference]:
    """``ensure_reference`` for several frames of one scene, in the order given, in one
    Cycles session (persistent data on throughout, so static volumes are synced once).

    ``on_frame(reference)`` runs as soon as each is ready (cached or rendered), so a cancel
    (``Cancelled``, between frames or after the current render) keeps the frames before it.
    The scene is left as it was found (frame, persistent data and every other setting).
    Cached frames cost no share of the progress; the user cache folder is checked for
    writing before the first render.
    """
    inputs = list(inputs)
    hits = [find_reference(item.key, environ) for item in inputs]
    folder = None
    if any(hit is None for hit in hits):
        folder = check_output_folder(user_folder(environ), "the reference cache")
    steps = WeightedSteps(progress, [0.0 if hit is not None else 1.0 for hit in hits])
    done: list[Reference] = []
    with preserved_scene(scene):
        scene.render.use_persistent_data = True
        for index, item in enumerate(inputs):
            label = f"frame {item.frame} ({index + 1}/{len(inputs)})"
            steps.begin(label)
            found = find_reference(item.key, environ)       # another process may have made it
            if found is not None:
                reference = _from_cache(found, item)
            else:
                if folder is None:              # a cached entry went away since the lookup
                    folder = check_output_folder(user_folder(environ), "the reference cache")
                image, run = render_reference(scene, item, steps.sub(label, echo="uniform: "))
                entry = write_reference(folder, item, image, run, file_name=file_name)
                reference = Reference(entry.path, item, "rendered", run)
            steps.finish()
            if on_frame is not None:
                on_frame(reference)
            done.append(reference)
    return done


def _from_cache(found: CachedReference, inputs: ReferenceInputs) -> Reference:
    return Reference(found.path, inputs, found.source, ReferenceRun.from_json(found.record.get("stats")))


def render_reference(scene, inputs: ReferenceInputs, progress: ProgressCallback | None = None):
    """Render the reference (uniform, ``inputs.spp`` samples, ``inputs.seed``, denoised like
    every run) at ``inputs.frame`` and ``inputs.resolution``; returns (image, ReferenceRun)."""
    options = RenderOptions(max_spp=inputs.spp, seed=inputs.seed, resolution=inputs.resolution,
                            denoise=True).check()
    started = time.perf_counter()
    with preserved_scene(scene):
        scene.frame_set(inputs.frame)
        outcome = render_uniform(scene, options, spp=inputs.spp, progress=progress)
    return outcome.image, ReferenceRun(outcome.stats.to_json(keep=ReferenceRun.KEPT),
                                       time.perf_counter() - started)
