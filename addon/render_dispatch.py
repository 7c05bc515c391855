"""The one place a render mode becomes renders: a ``RenderRequest``
(``core.sampling.render_request``) turned into the frame job (``addon.frame_jobs``) that
renders it, for a still (call the job) or a frame range (``frames_steps``).

The command line's ``render``, the panel, batch, the contestants of ``curves`` and the
farm's tasks all come here; nothing else switches on the mode. The volume estimator
``auto`` is chosen per frame inside the job (``estimated_frame``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.progress import ProgressCallback
from ..core.sampling.sequence_budget import SequenceBudget
from ..core.sampling.render_options import RenderOptions
from ..core.sampling.render_request import RenderRequest
from .cycles import selective_render as sr
from .frame_jobs import (FrameJob, estimated_frame, guided_frame, map_frame, selective_frame,
                         single_render_frame)


def request_frame_job(request: RenderRequest, cache_dir: str | Path | None = None,
                      sequence: SequenceBudget | None = None, director_map: np.ndarray | None = None,
                      map_seconds: float = 0.0, progress: ProgressCallback | None = None) -> FrameJob:
    """The frame job of ``request`` (checked by the front end that made it), ``auto``'s
    estimator chosen per frame.

    Parameters
    ----------
    cache_dir
        Keeps the camera rays of the maps between frames (None: a still's own).
    sequence
        A guided range's shared time (``SequenceBudget``).
    director_map
        xs, xsl: a director map given as a file (at render size), read in ``map_seconds``;
        None: the maps are computed for each frame.
    progress
        Hears the samples of a gold, uniform or adaptive render (one Cycles render with no
        steps inside); None: the job announces the render as a step instead.
    """
    if request.scene_samples:
        # Our bug, not the user's: the front end skipped ``at_scene_samples``.
        raise ValueError("a request whose counts are the scene's must get them before it renders")
    traits = request.traits

    def make(chosen: RenderOptions) -> FrameJob:
        if traits.director_map:
            label = request.label or request.mode
            if director_map is not None:
                return map_frame(director_map, chosen, label, map_seconds)
            return selective_frame(request.map_options, chosen, request.mode, cache_dir, label)
        if traits.time_budget:
            return guided_frame(request.guided, request.map_options, chosen, cache_dir, sequence)
        render = _BASELINES[request.mode]
        return single_render_frame(lambda scene: render(scene, request, chosen, progress), request.mode,
                                   announce=progress is None)

    return estimated_frame(make, request.options, request.first_estimator_spp(still=sequence is None))


def _gold(scene, request: RenderRequest, options: RenderOptions, progress):
    return sr.render_gold(scene, options, progress=progress)


def _uniform(scene, request: RenderRequest, options: RenderOptions, progress):
    return sr.render_uniform(scene, options, spp=request.spp, seconds=request.seconds, progress=progress)


def _adaptive(scene, request: RenderRequest, options: RenderOptions, progress):
    threshold = request.noise_threshold if request.noise_threshold is not None \
        else sr.CYCLES_DEFAULT_NOISE_THRESHOLD
    return sr.render_adaptive(scene, options, request.seconds, threshold, progress=progress)


#: The modes rendered by one ordinary Cycles render of the scene at its current frame.
_BASELINES = {"gold": _gold, "uniform": _uniform, "adaptive": _adaptive}
