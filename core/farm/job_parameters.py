"""The parameters of a farm job: every knob of ``xsl-render render`` (and of the farm) as an
Open Job Description job parameter, with the value the bundle chose and the
``xsl-render farm-task`` option it feeds.

A parameter is a dict: its template definition plus ``value`` (``parameter_values.yaml``)
and ``flag`` (the farm-task option; None when the template itself uses it).
"""
from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ..maps.director import OPERATORS
from ..maps.options import MapOptions
from ..sampling.guided_plan import IMPORTANCE_MAPS, MAX_TIME_BUDGET
from ..sampling.render_options import MIN_TILE_SIZE, UNBOUNDED_SPP
from .farm_job import (DEVICES, MAX_FRAMES_PER_TASK, MIN_FARM_TIME_BUDGET, NO_CEILING,
                       SELECTIVE_MODES, FarmJob)
from .task_groups import MAX_GROUPS
from .worker_environment import worker_parameters


def _auto(value) -> str:
    return "auto" if value is None else f"{value}"


_SCENE = "Scene"
_MAPS = "Director maps (the paper's names)"
_FARM = "Farm"


def _ui(group: str, label: str, **more) -> dict:
    return {"userInterface": {"label": label, "groupLabel": group, **more}}


def _number(name, kind, value, flag, description, group, label, low=None, high=None):
    entry = {"name": name, "type": kind, "description": description, "default": value,
             "value": value, "flag": flag, **_ui(group, label)}
    if low is not None:
        entry["minValue"] = low
    if high is not None:
        entry["maxValue"] = high
    return entry


def _choice(name, value, allowed, flag, description, group, label):
    return {"name": name, "type": "STRING", "description": description, "default": value,
            "value": value, "allowedValues": list(allowed), "flag": flag,
            **_ui(group, label, control="DROPDOWN_LIST")}


def _text(name, value, flag, description, group, label):
    return {"name": name, "type": "STRING", "description": description, "default": value,
            "value": value, "minLength": 1, "flag": flag, **_ui(group, label)}


def _scene_parameters(job: FarmJob) -> list[dict]:
    return [
        {"name": "SceneFile", "type": "PATH", "objectType": "FILE", "dataFlow": "IN",
         "description": "The .blend file to render (never written).", "value": str(job.scene),
         "flag": None, **_ui(_SCENE, "Scene file", control="CHOOSE_INPUT_FILE",
                             fileFilters=[{"label": "Blender files", "patterns": ["*.blend"]}])},
        _text("SceneName", job.scene_name, "--scene-name", "Which scene of the file to render.",
              _SCENE, "Scene"),
        _text("Frames", job.frames, None, "Frames to render: 12, 1-250, 1-250:2 or a list such "
              "as 1-3,8.", _SCENE, "Frames"),
        {"name": "OutputDir", "type": "PATH", "objectType": "DIRECTORY", "dataFlow": "OUT",
         "description": "Folder for frame_NNNN.exr, its samples-per-pixel images and statistics "
                        "(work/ holds the maps, plans and rendered rectangles).",
         # A PATH default must be relative (to the bundle); an absolute folder is a value only.
         **({} if Path(job.output).is_absolute() else {"default": job.output}),
         "value": job.output, "flag": "--output",
         **_ui(_SCENE, "Output folder", control="CHOOSE_DIRECTORY")},
    ]


def _map_parameters(m: MapOptions) -> list[dict]:
    return [
        _number("Wx", "FLOAT", m.wx, "--wx", "Weight of X in XS.", _MAPS, "w_x", low=0.0),
        _number("Ws", "FLOAT", m.ws, "--ws", "Weight of S in XS.", _MAPS, "w_s", low=0.0),
        _choice("XsOp", m.xs_op, OPERATORS, "--xs-op", "How X and S combine.", _MAPS, "XS operator"),
        _number("Wxs", "FLOAT", m.wxs, "--wxs", "Weight of XS in XSL.", _MAPS, "w_xs", low=0.0),
        _number("Wl", "FLOAT", m.wl, "--wl", "Weight of L in XSL.", _MAPS, "w_l", low=0.0),
        _choice("XslOp", m.xsl_op, OPERATORS, "--xsl-op", "How XS and L combine.", _MAPS, "XSL operator"),
        _text("LightN", _auto(m.light_n), "--light-n", "Iterations n of eq. 6, or auto.", _MAPS, "n"),
        _text("LightSigmaBase", _auto(m.light_sigma_base), "--light-sigma-base",
              "sigma_base of eq. 6 in pixels at 512 px, or auto.", _MAPS, "sigma_base"),
        {**_choice("MinBound", "true" if m.minbound else "false", ("true", "false"), "--minbound-value",
                   "Fill sky pixels with the smallest finite X.", _MAPS, "MinBound"),
         "userInterface": {"label": "MinBound", "groupLabel": _MAPS, "control": "CHECK_BOX"}},
    ]


def _farm_parameters(job: FarmJob) -> list[dict]:
    """Frames per task, the device, the xsl-render command and how a worker gets it."""
    return [
        _number("FramesPerTask", "INT", job.frames_per_task, None, "Frames each task renders in "
                "one Blender process, Cycles syncing the scene once for all of them (Open Job "
                "Description spreads the frames evenly over as many tasks as this needs). The "
                "tasks' timeout was fixed with the bundle for its own value: write the bundle "
                "again (--frames-per-task) to raise it far.", _FARM, "Frames per task", low=1,
                high=MAX_FRAMES_PER_TASK),
        _choice("Device", job.device, DEVICES, "--device", "Cycles device of every render. The "
                "steps' host requirements (a GPU or not) were fixed with the bundle: write it "
                "again to change device.", _FARM, "Cycles device"),
        _text("XslRender", job.executable, None, "The xsl-render command on the farm's machines "
              "(a name is looked up on the worker's PATH, after the worker setup's environment).",
              _FARM, "xsl-render executable"),
        *worker_parameters(job.worker),
    ]


def _selective_parameters(job: FarmJob) -> list[dict]:
    """The parameters of an xs / xsl job (steps Maps, Tiles, Composite)."""
    o = job.options
    width, height = o.resolution
    render = "Selective rendering"
    tiles = "Tiles"
    return [
        *_scene_parameters(job),
        _choice("Mode", job.mode, SELECTIVE_MODES, "--mode", "Director map: xs (transmittance and "
                "saliency) or xsl (also the glow of lights).", render, "Director map"),
        _number("MaxSpp", "INT", o.max_spp, "--max-spp", "Samples per pixel where the map is 1 "
                "(the gold standard's count).", render, "Max samples per pixel", low=1),
        _text("Resolution", f"{width}x{height}", "--resolution", "Render resolution WxH.", render,
              "Resolution"),
        _number("Seed", "INT", o.seed, "--seed", "Cycles seed of every render.", render, "Seed", low=0),
        *_map_parameters(job.map_options),
        _number("MinSpp", "INT", o.min_spp, "--min-spp", "Samples floor per pixel.", tiles,
                "Min samples per pixel", low=1),
        _number("TileSize", "INT", o.tile_size, "--tile-size", "Tile edge in pixels.", tiles,
                "Tile size", low=MIN_TILE_SIZE),
        _number("TileQuantile", "FLOAT", o.tile_quantile, "--tile-quantile", "Quantile of a tile's "
                "per-pixel targets it renders with (1 = max).", tiles, "Tile quantile", low=0.0, high=1.0),
        _number("SppLevels", "INT", o.spp_levels, "--spp-levels", "Round tile samples up to N "
                "geometric levels (0 = off).", tiles, "Sample levels", low=0),
        _number("Margin", "INT", o.margin, "--margin", "Pixels rendered around each rectangle and "
                "cropped.", tiles, "Margin", low=0, high=64),
        _number("RenderCost", "INT", o.render_cost, "--render-cost", "Fixed cost of one render in "
                "pixel-samples.", tiles, "Render cost", low=0),
        _text("AdaptiveThreshold", "off" if o.adaptive_threshold is None else f"{o.adaptive_threshold}",
              "--adaptive-threshold", "Cycles adaptive sampling inside each rectangle (noise "
              "threshold), or off.", tiles, "Adaptive threshold"),
        _number("TasksPerFrame", "INT", job.tasks_per_frame, None, "Tile tasks per frame; the "
                "rectangles are shared between them at about equal cost.", _FARM, "Tile tasks per frame",
                low=1, high=MAX_GROUPS),
        *_farm_parameters(job),
    ]


def _guided_parameters(job: FarmJob) -> list[dict]:
    """The parameters of a guided job (one step, Render): every knob of
    ``xsl-render render --mode guided``; the map options count when Importance names a map."""
    g, o = job.guided, job.options
    width, height = o.resolution
    render = "Guided rendering"
    return [
        *_scene_parameters(job),
        _number("TimeBudget", "FLOAT", g.time_budget, "--time-budget", "Seconds for the whole "
                "render of each frame: importance map, scene sync, passes, denoising.", render,
                "Time budget (s)", low=MIN_FARM_TIME_BUDGET, high=MAX_TIME_BUDGET),
        _choice("Importance", g.importance, IMPORTANCE_MAPS, "--importance", "Director map that "
                "weighs the estimated error: none, x, xs or xsl (computed inside the budget).",
                render, "Importance map"),
        _number("MaxSpp", "INT", o.max_spp if o.has_ceiling else NO_CEILING, "--max-spp", "Most samples any pixel "
                f"may get; {NO_CEILING}: no ceiling.", render, "Max samples per pixel",
                low=NO_CEILING, high=UNBOUNDED_SPP),
        _text("Resolution", f"{width}x{height}", "--resolution", "Render resolution WxH.", render,
              "Resolution"),
        _number("Seed", "INT", o.seed, "--seed", "Cycles seed of every render.", render, "Seed", low=0),
        _number("PilotFraction", "FLOAT", g.pilot_fraction, "--pilot-fraction", "Share of the "
                "budget the pilot pass may take, in (0, 1].", render, "Pilot fraction", high=1.0),
        _number("GuidedExponent", "FLOAT", g.exponent, "--guided-exponent", "Samples go as (error "
                "score x importance) to this power; 0 is uniform.", render, "Allocation exponent",
                low=0.0, high=2.0),
        _number("LevelRatio", "FLOAT", g.level_ratio, "--level-ratio", "Sample counts are rounded "
                "to powers of this ratio, in (1, 4].", render, "Level ratio", high=4.0),
        _number("TileSize", "INT", o.tile_size, "--tile-size", "Edge of the tiles the samples are "
                "allocated on, in pixels.", render, "Tile size", low=MIN_TILE_SIZE),
        *_map_parameters(job.map_options),
        *_farm_parameters(job),
    ]


def parameters(job: FarmJob) -> list[dict]:
    """Job parameter definitions with their values (``value``) and the
    ``xsl-render farm-task`` option each one feeds (``flag``; None: the template uses it)."""
    return _guided_parameters(job) if job.traits.time_budget else _selective_parameters(job)


def definition(parameter: dict) -> dict:
    return {key: value for key, value in parameter.items() if key not in ("value", "flag")}


def checked_parameters(job: FarmJob) -> list[dict]:
    """``parameters`` of the checked job, every value inside its parameter's bounds (a value
    the farm's form would refuse is refused now, naming its option)."""
    found = parameters(job.check())
    for p in found:
        low, high = p.get("minValue"), p.get("maxValue")
        if (low is None or p["value"] >= low) and (high is None or p["value"] <= high):
            continue
        if low is not None and high is not None:
            bounds = f"between {low} and {high}"
        else:
            bounds = f"at least {low}" if low is not None else f"at most {high}"
        raise InputError(f"{p['flag'] or p['name']} must be {bounds} in a farm job (got {p['value']})")
    return found


def task_arguments(parameters: list[dict]) -> list[str]:
    """Every parameter with a farm-task option, as that option and the parameter's value."""
    return [item for p in parameters if p["flag"] and p["name"] != "OutputDir"
            for item in (p["flag"], f"{{{{Param.{p['name']}}}}}")]
