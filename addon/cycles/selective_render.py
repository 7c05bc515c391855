"""Selective rendering (the paper's section 5) and the baselines it is measured against.

``render_selective`` scales ``options.max_spp`` per pixel by the director map; the tile plan
(``core.sampling.tile_plan``) turns that into rectangles, each rendered by Cycles with its own
samples and composited (``selective_steps``: the same run as steps, for the panel). The
baselines: ``render_gold`` (``max_spp`` everywhere), ``render_uniform`` (one count everywhere,
or as many as a wall time allows, by Cycles' time limit) and ``render_adaptive`` (Cycles'
adaptive sampling, stopped by its time limit). Each leaves the scene as it found it
(``preserved_scene``) and returns a ``RenderOutcome``: image, samples per pixel, statistics."""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ...core.errors import InputError, SettingError
from ...core.progress import Progress, ProgressCallback, Steps, TileProgress, run_steps
from ...core.sampling.composite import Compositor, crop, render_window
from ...core.sampling.finite_pixels import non_finite_warning, zero_non_finite
from ...core.sampling.render_options import RenderOptions
from ...core.sampling.render_stats import RenderStats
from ...core.sampling.tile_plan import Rect, check_director_map, make_plan
from ..scene.carriers import kept_reason
from ..scene.changes import ChangeRecord
from ..scene.geometry import step_setting
from ..scene.probe import camera_model, render_size
from ..scene.state import preserved_scene, scene_changes
from .sample_pattern import apply_sample_pattern
from .tile_render import CyclesWindowRenderer, RenderedWindow

#: Cycles' own default noise threshold, what an artist switching adaptive sampling on gets.
CYCLES_DEFAULT_NOISE_THRESHOLD = 0.01
#: Window rendered at 1 sample before a time-limited render, so that the scene sync and BVH
#: build (which Cycles' time limit does not count) are paid inside the budget, not on top.
_WARMUP_SIZE = 8


@dataclass
class RenderOutcome:
    """What one run produced."""

    image: np.ndarray                       # (H, W, 4) float32 RGBA, row 0 at the top
    samples: np.ndarray                     # (H, W) float32 samples per pixel
    stats: RenderStats
    warnings: list[str] = field(default_factory=list)


def prepare_render(scene, options: RenderOptions) -> tuple[int, int, list[str]]:
    """Apply the resolution option, check the camera, warn about a non-Cycles engine.

    Must run inside ``preserved_scene``. Returns (width, height, warnings). The options were
    checked where they were made.
    """
    if options.resolution is not None:
        scene.render.resolution_x, scene.render.resolution_y = options.resolution
        scene.render.resolution_percentage = 100
    camera_model(scene)                     # InputError for a missing or non-camera camera
    warnings = apply_estimator(scene, options.volume_estimator())
    if scene.render.engine != "CYCLES":
        warnings.append(f"scene '{scene.name}' renders with {scene.render.engine}; this run "
                        f"uses Cycles (the scene keeps {scene.render.engine})")
    width, height = render_size(scene)
    return width, height, warnings


def apply_estimator(scene, choice, changes: ChangeRecord | None = None) -> list[str]:
    """Set Cycles' volume estimator as ``choice`` says, the materials' and the world's own
    steps too where auto gave some media coarser ones, and the sample pattern, the light
    tree and (while it ray-marches) the media's volume sampling where auto chose them.

    Every setting goes through ``changes`` (by default the record of the innermost
    ``preserved_scene`` block, ``scene_changes``), which puts it back; a medium's material
    or world is found by identity (``addon.scene.carriers``). Returns warnings: a medium
    whose settings may not be changed (linked from a library) keeps its own."""
    changes = changes if changes is not None else scene_changes(scene)
    if choice.sample_pattern is not None:
        apply_sample_pattern(scene, choice.sample_pattern, changes)
    if choice.light_tree is not None:
        changes.set(scene.cycles, "use_light_tree", choice.light_tree)
    if choice.biased is None:
        return []
    changes.set(scene.cycles, "volume_biased", bool(choice.biased))
    if choice.biased and choice.step_rate is not None:
        changes.set(scene.cycles, "volume_step_rate", float(choice.step_rate))
    # (A settle from ray marching to null scattering puts the media's own methods back.)
    methods = (choice.scatter_sampling if choice.biased else choice.scatter_own) or {}
    settings = [(key, "volume_sampling", method) for key, method in methods.items()]
    settings += [(key, None, float(value)) for key, value in (choice.medium_settings or {}).items()]
    warnings = []
    for key, name, value in settings:
        kept = kept_reason(key)
        if kept is not None:
            warnings.append(kept)
            continue
        struct, step = step_setting(key)
        changes.set(struct, name or step, value)
    return list(dict.fromkeys(warnings))


def render_stats(mode: str, scene, options: RenderOptions, width: int, height: int,
                 samples: np.ndarray, phases: dict, tiles: list[dict], warnings: list[str],
                 cycles_sync_s: float | None = None, denoise_guides: dict | None = None,
                 non_finite_pixels: int = 0) -> RenderStats:
    """What every mode records (``phases`` is kept, not copied: later phases add to it;
    ``warnings`` too, which gets a line where ``non_finite_pixels`` were set to 0)."""
    if non_finite_pixels:
        warnings.append(non_finite_warning(non_finite_pixels))
    total = float(samples.sum(dtype=np.float64))
    estimator = options.volume_estimator()
    if estimator.seconds:
        # Auto's prediction is part of the run (a phase, counted in its time).
        phases.setdefault("estimator", estimator.seconds)
    return RenderStats(
        mode=mode, scene=scene.name, resolution=(width, height), max_spp=options.max_spp,
        seed=options.seed, phases_s=phases, total_samples=int(round(total)),
        mean_spp=total / (width * height), gold_samples=width * height * options.max_spp,
        renders=len(tiles), tiles=tiles, options=options.to_dict(),
        estimator=estimator.to_dict() | {"described": estimator.describe()}, warnings=warnings,
        cycles_sync_s=cycles_sync_s, denoise_guides=denoise_guides,
        non_finite_pixels=non_finite_pixels or None)


def tile_entry(window, rendered) -> dict:
    row0, row1, col0, col1 = window
    return {"row0": row0, "row1": row1, "col0": col0, "col1": col1,
            "spp": rendered.samples_set, "samples_rendered": rendered.samples_rendered,
            "mean_spp": float(np.mean(rendered.samples)), "seconds": rendered.seconds}


@dataclass
class RenderedRect:
    """One rectangle of a plan, rendered and cropped to its own pixels."""

    rect: Rect
    window: tuple[int, int, int, int]       # what Cycles rendered: the rectangle and its margin
    pixels: np.ndarray                      # (h, w, 4) float32 RGBA of the rectangle only
    samples: np.ndarray | int               # samples per pixel: a number, or (h, w) counts
    rendered: RenderedWindow
    guides: np.ndarray | None = None        # (h, w, 6) denoising albedo + normal, cropped


def render_rect(renderer: CyclesWindowRenderer, rect: Rect, options: RenderOptions) -> RenderedRect:
    """Render one rectangle of a plan (grown by ``options.margin``) and crop it back.

    The one place a plan's rectangle becomes pixels, for ``render_selective`` and for the
    farm's tile tasks alike, so both give the same image.
    """
    window = render_window(rect.window, options.margin, renderer.width, renderer.height)
    rendered = renderer.render(window, rect.spp, adaptive_threshold=options.noise_threshold(rect.spp))
    samples = rendered.samples
    if isinstance(samples, np.ndarray):
        samples = crop(samples, window, rect.window)
    guides = None if rendered.guides is None else crop(rendered.guides, window, rect.window)
    return RenderedRect(rect, window, crop(rendered.pixels, window, rect.window), samples, rendered, guides)


def finish_image(image: np.ndarray, guides: np.ndarray | None, options: RenderOptions,
                 phases: dict, prefilter: bool, allow_prefilter: bool = True) -> tuple[np.ndarray, dict | None, int]:
    """The frame as delivered: its infinite or NaN pixels set to 0 (``core.sampling.
    finite_pixels``: InputError when all are), denoised once, whole (``options.denoise``),
    timed as a phase, its guides denoised first where the file's denoiser does so
    (``prefilter``: ``guide_prefilter``); how noisy the guides were and whether they were
    prefiltered (``RenderStats.denoise_guides``), and the number of pixels set to 0.
    ``allow_prefilter`` False: the caller could not afford the prefilter (``guided``)."""
    image, non_finite = zero_non_finite(image)
    if not options.denoise:
        return image, None, non_finite
    from ...core.sampling.denoise_guides import NOISY_GUIDE_MEDIAN, guide_noise
    from .denoise import denoise

    started = time.perf_counter()
    record = None
    if guides is not None:
        noise = guide_noise(guides[..., :3])
        record = {"noise": noise, "noisy": noise > NOISY_GUIDE_MEDIAN, "prefiltered": prefilter and allow_prefilter}
    out = denoise(image, None if guides is None else guides[..., :3],
                  None if guides is None else guides[..., 3:6],
                  prefilter_guides=bool(record and record["prefiltered"]))
    phases["denoise"] = time.perf_counter() - started
    return out, record, non_finite


def guide_prefilter(scene) -> bool:
    """Whether the file's denoiser denoises its albedo and normal guides first: OIDN's
    Accurate prefilter (Blender 5's default), which every mode follows, so that a run is
    denoised as the artist's own render would be."""
    return getattr(scene.cycles, "denoising_prefilter", "ACCURATE") == "ACCURATE"


def render_selective(scene, director_map: np.ndarray, options: RenderOptions,
                     progress: ProgressCallback | None = None, mode: str = "xsl",
                     map_seconds: float = 0.0) -> RenderOutcome:
    """Render ``scene`` with samples per pixel set by ``director_map`` (section 5 of the paper).

    Parameters
    ----------
    scene
        A Blender scene with an active camera (any engine: Cycles is used and the engine put back).
    director_map
        (H, W) values in [0, 1] at the render resolution (after ``options.resolution``).
    options
        Ceiling, floor, tiles, seed, margin, optional per-rectangle adaptive sampling.
    progress
        ``callback(fraction, message)``; returning True cancels between two renders.
    mode
        Name recorded in the statistics ("xs", "xsl", ...).
    map_seconds
        Time already spent making the map, recorded as the "maps" phase.
    """
    return run_steps(selective_steps(scene, director_map, options, mode, map_seconds), progress)


def selective_steps(scene, director_map: np.ndarray, options: RenderOptions, mode: str = "xsl",
                    map_seconds: float = 0.0) -> Steps[RenderOutcome]:
    """``render_selective`` as steps (``core.progress``): yields before and after every tile
    render, returns the ``RenderOutcome``. Closing it between two steps restores the scene."""
    with preserved_scene(scene):
        width, height, warnings = prepare_render(scene, options)
        started = time.perf_counter()
        data = check_director_map(director_map, width, height)
        plan = make_plan(data, options)
        phases = {"maps": map_seconds, "plan": time.perf_counter() - started}
        tracker = TileProgress(Progress(), [rect.samples for rect in plan.rects], options.render_cost)
        compositor = Compositor(width, height)
        guides = Compositor(width, height, channels=6) if options.denoise else None
        tiles, composite_s, waited = [], 0.0, 0.0
        started = time.perf_counter()
        with CyclesWindowRenderer(scene, options.seed, guides=options.denoise) as renderer:
            for rect in plan.rects:
                paused = time.perf_counter()
                yield tracker.start(rect.spp)
                waited += time.perf_counter() - paused
                piece = render_rect(renderer, rect, options)
                placed = time.perf_counter()
                compositor.add(rect.window, piece.pixels, piece.samples)
                if guides is not None:
                    guides.add(rect.window, piece.guides, piece.samples)
                composite_s += time.perf_counter() - placed
                tiles.append(tile_entry(rect.window, piece.rendered) | {"window": list(piece.window)})
                paused = time.perf_counter()
                yield tracker.finish()
                waited += time.perf_counter() - paused
        # Time spent between steps (a modal operator waiting for its next timer tick) is
        # not rendering time.
        phases["renders"] = time.perf_counter() - started - composite_s - waited
        started = time.perf_counter()
        image, samples = compositor.result()
        phases["composite"] = composite_s + time.perf_counter() - started
        image, denoise_guides, non_finite = finish_image(
            image, None if guides is None else guides.result()[0], options, phases, guide_prefilter(scene))
        stats = render_stats(mode, scene, options, width, height, samples, phases, tiles, warnings,
                             renderer.sync_seconds, denoise_guides, non_finite)
    stats.plan, stats.ideal_speedup = plan.to_dict(), plan.ideal_speedup
    stats.director_map_mean = float(data.mean())
    return RenderOutcome(image, samples, stats, warnings)


def _single_render(scene, options: RenderOptions, mode: str, progress: ProgressCallback | None,
                   samples: int, time_budget: float | None = None,
                   adaptive_threshold: float | None = None, budget: str | None = None) -> RenderOutcome:
    """One ordinary Cycles render of the whole frame (optionally time-limited)."""
    report = Progress(progress)
    with preserved_scene(scene):
        width, height, warnings = prepare_render(scene, options)
        phases = {"maps": 0.0}
        started = time.perf_counter()
        tiles = []
        with CyclesWindowRenderer(scene, options.seed, guides=options.denoise) as renderer:
            report.update(0.0, f"{mode}: rendering")
            time_limit = 0.0
            if time_budget is not None:
                # Sync the scene (persistent data) inside the budget, then give Cycles the rest.
                # The warm-up has the real render's passes and sampling mode: any difference
                # would make Cycles sync the scene again (seconds with heterogeneous volumes).
                row, col = (height - min(height, _WARMUP_SIZE)) // 2, (width - min(width, _WARMUP_SIZE)) // 2
                renderer.render((row, row + min(height, _WARMUP_SIZE), col, col + min(width, _WARMUP_SIZE)), 1,
                                adaptive_threshold=adaptive_threshold, time_limit=time_budget)
                # (Auto's prediction ran before, inside the budget, as guided counts it.)
                spent = time.perf_counter() - started + options.volume_estimator().seconds
                time_limit = max(0.01, time_budget - spent)
                began = time.perf_counter()

                def on_sample(done, total):
                    report.note((time.perf_counter() - began) / time_limit, f"{mode}: sample {done}")
            else:
                def on_sample(done, total):
                    report.note(done / max(1, total), f"{mode}: sample {done}/{total}")
            rendered = renderer.render(None, samples, adaptive_threshold=adaptive_threshold,
                                       time_limit=time_limit, on_sample=on_sample)
            tiles.append(tile_entry((0, height, 0, width), rendered))
        phases["renders"] = time.perf_counter() - started
        image, denoise_guides, non_finite = finish_image(rendered.pixels, rendered.guides, options, phases,
                                                         guide_prefilter(scene))
        report.update(1.0, f"{mode}: done")
        per_pixel = np.broadcast_to(np.float32(rendered.samples), (height, width)).astype(np.float32)
        stats = render_stats(mode, scene, options, width, height, per_pixel, phases, tiles, warnings,
                             renderer.sync_seconds, denoise_guides, non_finite)
    stats.budget, stats.noise_threshold = budget, adaptive_threshold
    if time_budget is not None:
        # Fewer passes than the ceiling and the whole limit used: the clock stopped it (not
        # adaptive sampling finding every pixel converged).
        stats.time_budget_s, stats.time_limit_s = time_budget, time_limit
        stats.stopped_by_time = (rendered.samples_rendered < samples
                                 and rendered.seconds >= 0.9 * time_limit)
    return RenderOutcome(image, per_pixel, stats, warnings)


def render_gold(scene, options: RenderOptions, progress: ProgressCallback | None = None) -> RenderOutcome:
    """The gold standard: ``options.max_spp`` samples in every pixel, one ordinary render."""
    return _single_render(scene, options, "gold", progress, options.max_spp)


def render_uniform(scene, options: RenderOptions, spp: int | None = None, seconds: float | None = None,
                   progress: ProgressCallback | None = None) -> RenderOutcome:
    """The same samples in every pixel: ``spp`` of them (equal cost: the selective run's
    mean), or as many as fit in ``seconds`` of wall time (at most ``options.max_spp``)."""
    if (spp is None) == (seconds is None):
        raise InputError("uniform mode needs either a sample count or a time budget")
    if spp is not None:
        if spp < 1:
            raise InputError(f"uniform samples per pixel must be at least 1 (got {spp})")
        return _single_render(scene, options, "uniform", progress, spp, budget="samples")
    if not seconds > 0:
        raise InputError(f"the time budget must be positive (got {seconds})")
    return _single_render(scene, options, "uniform", progress, options.max_spp, time_budget=seconds,
                          budget="time")


def render_adaptive(scene, options: RenderOptions, seconds: float | None,
                    noise_threshold: float = CYCLES_DEFAULT_NOISE_THRESHOLD,
                    progress: ProgressCallback | None = None) -> RenderOutcome:
    """Cycles' adaptive sampling with ``max_spp`` as the ceiling, stopped at ``seconds`` of wall
    time by Cycles' time limit (it may finish sooner if every pixel reaches the threshold).
    ``seconds`` None: no time limit, Cycles stops where every pixel reaches the threshold
    or at the ceiling (a point of the adaptive time-quality curve, ``xsl-render curves``).

    Why the time limit and not a tuned threshold: the threshold that makes Cycles finish in
    exactly ``seconds`` can only be found by trial renders, which cost more than the budget;
    the time limit meets it in one render. The scene is synced by a 1-sample render of a few
    pixels first (persistent data keeps it), so the sync that Cycles' limit does not count
    is paid inside the budget. The threshold is Cycles' default unless given: what an artist
    who switches on adaptive sampling and a time limit gets.
    """
    if seconds is not None and not seconds > 0:
        raise InputError(f"the time budget must be positive (got {seconds})")
    if not noise_threshold > 0:
        raise SettingError("{noise_threshold.name} must be positive (got {noise_threshold.value})",
                           noise_threshold=noise_threshold)
    return _single_render(scene, options, "adaptive", progress, options.max_spp, time_budget=seconds,
                          adaptive_threshold=noise_threshold,
                          budget="samples" if seconds is None else "time")
