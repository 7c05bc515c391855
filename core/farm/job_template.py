"""An Open Job Description job template (specification 2023-09) for a selective or guided render.

A selective job (``xs``, ``xsl``: the paper) has three steps, each a command of the
``xsl-render`` executable:

1. ``Maps`` — one task per frame: the director maps of the frame and its tile plan
   (``xsl-render farm-task maps``);
2. ``Tiles`` — Frame x Group tasks, ``Group`` = 1..TasksPerFrame: each task renders its share
   of the frame's plan, split so that the tasks of a frame cost about the same
   (``core.farm.task_groups``; the plan only exists once the maps are computed, so the template
   fixes the number of tasks, not the rectangles). Depends on Maps;
3. ``Composite`` — one task per frame: the final EXR and samples-per-pixel image. Depends on
   Maps and Tiles.

A guided job (``xsl-render render --mode guided``) has one step, ``Render``: one task per
frame renders it within the time budget (``xsl-render farm-task guided``). Its passes follow
the clock of one process, so a frame is not split between tasks; frames are.

Every knob is a job parameter (a farm's submitter shows them as a form; the values chosen
are recorded with the job): the scene file (a PATH, so the farm can map it between machines),
the scene in it, the frames (an Open Job Description range expression such as ``1-250`` or
``1-99:2``), the output folder, the paper's map options, the tile options of
``xsl-render render`` and the number of tile tasks per frame (selective) or the time budget
and the guided sampler's options (guided), and the ``xsl-render`` executable.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from ..errors import InputError
from ..frames import parse_frame_range
from ..maps.director import OPERATORS
from ..maps.options import MapOptions
from ..sampling.guided_plan import IMPORTANCE_MAPS, MAX_TIME_BUDGET, UNBOUNDED_SPP, GuidedOptions
from ..sampling.render_options import MIN_TILE_SIZE, RenderOptions
from .task_groups import MAX_GROUPS, check_groups

SPECIFICATION = "jobtemplate-2023-09"
SELECTIVE_MODES = ("xs", "xsl")
GUIDED = "guided"
MODES = (*SELECTIVE_MODES, GUIDED)
#: MaxSpp of a guided job without a per-pixel ceiling. An INT parameter cannot be empty, and
#: 0 samples per pixel means nothing else, so the farm's form can still check the number.
NO_CEILING = 0
#: The shortest time budget a guided job takes: a job parameter's minimum is inclusive, and
#: the budget must be more than 0 (nothing renders in a millisecond; the bound only keeps the
#: form's check honest).
MIN_FARM_TIME_BUDGET = 0.001


def parse_frames(text: str) -> str:
    """'12', '1-250' or '1-250:2' -> the same range in canonical form; InputError otherwise."""
    frames = parse_frame_range(text)
    start, end, step = frames.start, frames.stop - 1, frames.step
    if start == end:
        return str(start)
    return f"{start}-{end}" + (f":{step}" if step != 1 else "")


@dataclass(frozen=True)
class FarmJob:
    """Everything a farm job of one scene renders, as the bundle's parameter values."""

    scene: Path                     # absolute path of the .blend
    scene_name: str
    frames: str                     # canonical range (parse_frames)
    output: str                     # folder; relative paths are relative to the bundle
    mode: str
    map_options: MapOptions
    options: RenderOptions          # its resolution must be set (the farm never guesses)
    tasks_per_frame: int            # tile tasks per frame (selective; a guided frame is one task)
    executable: str                 # the xsl-render command on the farm's machines
    guided: GuidedOptions | None = None     # the time budget and its options (guided only)

    def check(self) -> "FarmJob":
        if self.mode not in MODES:
            raise InputError(f"--mode must be one of {', '.join(MODES)} for a farm job (got '{self.mode}')")
        if self.options.resolution is None:
            raise InputError("a farm job needs its resolution fixed")
        self.options.check()
        width, height = self.options.resolution
        if self.mode == GUIDED:
            if self.guided is None:
                raise InputError("--mode guided needs --time-budget SECONDS")
            self.guided.check()
            replace(self.options, tile_size=self.guided.tile_size).check_frame(width, height)
        elif self.guided is not None:
            raise InputError(f"--time-budget is for --mode guided (got --mode {self.mode})")
        self.options.check_frame(width, height)
        self.map_options.validate()
        check_groups(self.tasks_per_frame)
        parse_frames(self.frames)
        return self


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
        _text("Frames", job.frames, None, "Frames to render: 12, 1-250 or 1-250:2.", _SCENE, "Frames"),
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


def _executable_parameter(job: FarmJob) -> dict:
    return _text("XslRender", job.executable, None, "The xsl-render command on the farm's machines.",
                 _FARM, "xsl-render executable")


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
        _executable_parameter(job),
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
        _number("MaxSpp", "INT", g.max_spp or NO_CEILING, "--max-spp", "Most samples any pixel "
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
        _number("TileSize", "INT", g.tile_size, "--tile-size", "Edge of the tiles the samples are "
                "allocated on, in pixels.", render, "Tile size", low=MIN_TILE_SIZE),
        *_map_parameters(job.map_options),
        _executable_parameter(job),
    ]


def _parameters(job: FarmJob) -> list[dict]:
    """Job parameter definitions with their values (``value``) and the
    ``xsl-render farm-task`` option each one feeds (``flag``; None: the template uses it)."""
    return _guided_parameters(job) if job.mode == GUIDED else _selective_parameters(job)


def _definition(parameter: dict) -> dict:
    return {key: value for key, value in parameter.items() if key not in ("value", "flag")}


def _action(*args: str) -> dict:
    return {"onRun": {"command": "{{Param.XslRender}}", "args": ["farm-task", *args]}}


def _frame_space(**more) -> dict:
    definitions = [{"name": "Frame", "type": "INT", "range": "{{Param.Frames}}"}]
    for name, value_range in more.items():
        definitions.append({"name": name, "type": "INT", "range": value_range})
    return {"taskParameterDefinitions": definitions}


def _checked_parameters(job: FarmJob) -> list[dict]:
    """``_parameters`` of the checked job, every value inside its parameter's bounds (a value
    the farm's form would refuse is refused now, naming its option)."""
    parameters = _parameters(job.check())
    for p in parameters:
        low, high = p.get("minValue"), p.get("maxValue")
        if (low is None or p["value"] >= low) and (high is None or p["value"] <= high):
            continue
        if low is not None and high is not None:
            bounds = f"between {low} and {high}"
        else:
            bounds = f"at least {low}" if low is not None else f"at most {high}"
        raise InputError(f"{p['flag'] or p['name']} must be {bounds} in a farm job (got {p['value']})")
    return parameters


def _task_arguments(parameters: list[dict]) -> list[str]:
    """Every parameter with a farm-task option, as that option and the parameter's value."""
    return [item for p in parameters if p["flag"] and p["name"] != "OutputDir"
            for item in (p["flag"], f"{{{{Param.{p['name']}}}}}")]


def job_template(job: FarmJob) -> dict:
    """The job template as plain data (dump it as YAML or JSON)."""
    parameters = _checked_parameters(job)
    frame = ["--frame", "{{Task.Param.Frame}}", "--output", "{{Param.OutputDir}}"]
    if job.mode == GUIDED:
        return _guided_template(parameters, frame)
    map_args = _task_arguments(parameters)
    return {
        "specificationVersion": SPECIFICATION,
        "name": "xsl-render {{Param.SceneName}} frames {{Param.Frames}}",
        "description": "Perceptual selective rendering of participating media (Sundstedt et al. "
                       "2007) with Blender Cycles: director maps, tile renders, composite.",
        "parameterDefinitions": [_definition(p) for p in parameters],
        "steps": [
            {"name": "Maps",
             "description": "Director maps and the tile plan of each frame.",
             "parameterSpace": _frame_space(),
             "script": {"actions": _action("maps", "{{Param.SceneFile}}", *frame, *map_args)}},
            {"name": "Tiles",
             "description": "Each task renders its share of a frame's rectangles.",
             "parameterSpace": {**_frame_space(Group="1-{{Param.TasksPerFrame}}"),
                                "combination": "Frame * Group"},
             "script": {"actions": _action("tiles", "{{Param.SceneFile}}", *frame,
                                           "--group", "{{Task.Param.Group}}",
                                           "--groups", "{{Param.TasksPerFrame}}")},
             "dependencies": [{"dependsOn": "Maps"}]},
            {"name": "Composite",
             "description": "The final image and samples-per-pixel image of each frame.",
             "parameterSpace": _frame_space(),
             "script": {"actions": _action("composite", *frame, "--groups", "{{Param.TasksPerFrame}}")},
             "dependencies": [{"dependsOn": "Maps"}, {"dependsOn": "Tiles"}]},
        ],
    }


def _guided_template(parameters: list[dict], frame: list[str]) -> dict:
    return {
        "specificationVersion": SPECIFICATION,
        "name": "xsl-render guided {{Param.SceneName}} frames {{Param.Frames}}",
        "description": "Rendering of participating media with Blender Cycles within a time budget "
                       "per frame: a pilot pass, the rest of the budget where the denoised frame "
                       "keeps its error (xsl-render render --mode guided).",
        "parameterDefinitions": [_definition(p) for p in parameters],
        "steps": [
            {"name": "Render",
             "description": "Each task renders one frame within the time budget.",
             "parameterSpace": _frame_space(),
             "script": {"actions": _action("guided", "{{Param.SceneFile}}", *frame,
                                           *_task_arguments(parameters))}},
        ],
    }


def parameter_values(job: FarmJob) -> dict:
    """``parameter_values.yaml`` of the job bundle, in the layout AWS Deadline Cloud reads.

    A relative PATH is left out: its template default is resolved against the bundle folder
    (by Deadline Cloud and ``openjd`` alike), where a relative *value* would be resolved
    against whatever folder the job is submitted or run from.
    """
    return {"parameterValues": [{"name": p["name"], "value": p["value"]}
                                for p in _checked_parameters(job)
                                if not (p["type"] == "PATH" and not Path(p["value"]).is_absolute())]}


def openjd_values(values: dict) -> dict:
    """``parameter_values`` as the mapping ``openjd run --job-param`` takes (name -> value)."""
    return {entry["name"]: entry["value"] for entry in values["parameterValues"]}
