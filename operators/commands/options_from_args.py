"""The command line's options as core's typed records: ``RenderOptions``, ``GuidedOptions``,
``MapOptions``, and the whole ``RenderRequest`` of ``xsl-render render`` (its budget read from
--budget-from's stats file), each checked once. The flags are declared in ``common.py``;
what a mode takes is the request's own check (``core.sampling.render_request``).
"""
from __future__ import annotations

import json
from pathlib import Path

from ...core.errors import InputError
from ...core.maps.options import MapOptions
from .common import parse_resolution


def guided_options_from_args(args):
    """``GuidedOptions`` from the time budget's arguments (checked with the request that holds
    them; its ceiling and tile size are the render options')."""
    from ...core.sampling.guided_plan import GuidedOptions

    if args.time_budget is None:
        raise InputError("--mode guided needs --time-budget SECONDS")
    return GuidedOptions(time_budget=args.time_budget, pilot_fraction=args.pilot_fraction,
                         exponent=args.exponent, importance=args.importance,
                         level_ratio=args.level_ratio)


def guided_render_options(args, resolution):
    """``RenderOptions`` of a guided render made outside ``xsl-render render`` (the farm),
    checked: --max-spp as its ceiling (none given, or 0: ``UNBOUNDED_SPP``), --tile-size,
    --seed, the resolution and --estimator (auto where the command has none)."""
    from ...core.sampling.render_options import UNBOUNDED_SPP, RenderOptions

    return RenderOptions(max_spp=args.max_spp or UNBOUNDED_SPP, tile_size=args.tile_size, seed=args.seed,
                         resolution=resolution, estimator=getattr(args, "estimator", "auto")).check()


def render_options_from_args(args, counts_from_scene: bool = False):
    """``RenderOptions`` from --max-spp, the tile options, --seed and --resolution, unchecked
    (the request that holds them checks them).

    Without --max-spp a time budget has no ceiling (``UNBOUNDED_SPP``) and uniform given --spp
    alone takes that count; otherwise the count is the scene's (``counts_from_scene``: a
    stand-in until ``RenderRequest.at_scene_samples``) or InputError."""
    from ...core.checks import MAX_SAMPLES
    from ...core.sampling.render_options import UNBOUNDED_SPP, RenderOptions
    from ...core.sampling.render_request import MODE_TRAITS, ModeTraits

    max_spp, mode = args.max_spp, getattr(args, "mode", None)
    traits = MODE_TRAITS.get(mode, ModeTraits())
    if max_spp is None and traits.spp and getattr(args, "spp", None) is not None:
        max_spp = args.spp
    if max_spp is None:
        if traits.time_budget:
            max_spp = UNBOUNDED_SPP
        elif counts_from_scene:
            max_spp = MAX_SAMPLES
        else:
            raise InputError(f"--mode {mode} needs --max-spp N" if mode else "--max-spp N is needed")
    return RenderOptions(
        max_spp=max_spp, min_spp=args.min_spp, tile_size=args.tile_size,
        tile_quantile=args.tile_quantile, spp_levels=args.spp_levels, seed=args.seed,
        margin=args.margin, render_cost=args.render_cost, adaptive_threshold=args.adaptive_threshold,
        resolution=parse_resolution(args.resolution), denoise=args.denoise,
        estimator=getattr(args, "estimator", "scene"), step_rate=getattr(args, "step_rate", None))


def map_options_from_args(args) -> MapOptions:
    return MapOptions(wx=args.wx, ws=args.ws, xs_op=args.xs_op, wxs=args.wxs, wl=args.wl,
                      xsl_op=args.xsl_op, light_n=args.light_n,
                      light_sigma_base=args.light_sigma_base, minbound=args.minbound).validate()


def read_budget(path: str):
    """The budget recorded in the stats file ``path`` (``RecordedBudget``)."""
    from ...core.sampling.render_stats import RecordedBudget

    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"no such stats file: {path}") from None
    except (OSError, ValueError, RecursionError) as error:
        raise InputError(f"cannot read stats file {path}: {str(error).splitlines()[0]}") from None
    return RecordedBudget.from_json(data, path)


def render_budget(budget, path: str) -> float:
    """Wall time an equal-time run may render for (``RecordedBudget.render_seconds``)."""
    seconds = budget.render_seconds
    if seconds <= 0.0:
        raise InputError(f"{path} leaves no time to render (wall_s less its denoising is {seconds:g} s)")
    return seconds


def render_request_from_args(args) -> tuple:
    """The ``RenderRequest`` of ``xsl-render render`` (checked), and the director map file an
    xs or xsl render reads instead of computing its maps (None without --map/--maps).

    Every flag goes into the request as given; what a mode takes is the request's own
    check (``MODE_TRAITS``). A stats file gives the budget its mode is measured by. Counts
    not given are the scene's samples (``RenderRequest.scene_samples``)."""
    from ...core.sampling.guided_plan import GuidedOptions
    from ...core.sampling.render_request import MODE_TRAITS, RenderRequest

    traits = MODE_TRAITS[args.mode]
    from_scene = args.max_spp is None and not traits.time_budget and not (traits.spp and args.spp is not None)
    options = render_options_from_args(args, counts_from_scene=from_scene)
    if traits.time_budget:
        guided = guided_options_from_args(args)
    elif args.time_budget is not None:
        # Refused by the request itself ("is for --mode guided"), before anything is read.
        RenderRequest(args.mode, options, guided=GuidedOptions(time_budget=args.time_budget)).check()
    else:
        guided = None
    map_file = None
    if traits.director_map and (args.map or args.maps):
        map_file = Path(args.map) if args.map else map_file_of(args)
    computes_maps = traits.computes_maps and not (traits.director_map and map_file is not None)
    if args.budget_from and not traits.budget_from:
        raise InputError(f"--budget-from is for --mode uniform and adaptive (got --mode {args.mode})")
    spp, seconds, mean_spp, budget_from = args.spp, None, None, None
    recorded = read_budget(args.budget_from) if args.budget_from else None
    if args.equal_time is not None and args.equal_time >= 0:
        if args.equal_time == 0:
            raise InputError("--equal-time must be positive (got 0)")
        seconds = args.equal_time
    elif args.equal_time is not None:           # --equal-time without SECONDS: the stats file's
        if recorded is None:
            raise InputError("--equal-time without SECONDS needs --budget-from STATS.json")
        seconds, budget_from = render_budget(recorded, args.budget_from), args.budget_from
    elif recorded is not None and spp is None:
        budget_from = args.budget_from
        if traits.budget_from == "spp":
            spp, mean_spp = max(1, int(round(recorded.mean_spp))), recorded.mean_spp
        else:
            seconds = render_budget(recorded, args.budget_from)
    if traits.spp and spp is None and seconds is None and not from_scene:
        spp = options.max_spp               # uniform without a budget renders its ceiling
    request = RenderRequest(args.mode, options, spp=spp, seconds=seconds, noise_threshold=args.noise_threshold,
                            guided=guided, map_options=map_options_from_args(args) if computes_maps else None,
                            budget_from=budget_from, budget_mean_spp=mean_spp, scene_samples=from_scene)
    return request.check(), map_file


def map_file_of(args) -> Path:
    """The map a selective render reads from --maps DIR: DIR/xs.exr or DIR/xsl.exr."""
    from ...core.sampling.render_request import MODE_TRAITS

    return Path(args.maps) / f"{args.mode if MODE_TRAITS[args.mode].director_map else 'xsl'}.exr"
