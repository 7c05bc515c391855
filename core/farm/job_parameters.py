"""The parameters of a farm job: every knob of ``xsl-render render`` (and of the farm) as an
Open Job Description job parameter, with the value the bundle chose and the
``xsl-render farm-task`` option it feeds.

A parameter is a dict: its template definition plus ``value`` (``parameter_values.yaml``)
and ``flag`` (the farm-task option; None when the template itself uses it).
"""
from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ..maps.options import MapOptions
from ..option_table import MAP_OPTIONS, OPTIONS
from ..sampling.render_options import UNBOUNDED_SPP
from .farm_job import MIN_FARM_TIME_BUDGET, NO_CEILING, SELECTIVE_MODES, FarmJob
from .worker_environment import worker_parameters


_SCENE = "Scene"
_MAPS = "Director maps (the paper's names)"
_FARM = "Farm"


def _ui(group: str, label: str, **more) -> dict:
    return {"userInterface": {"label": label, "groupLabel": group, **more}}


def _choice(name, value, allowed, flag, description, group, label):
    return {"name": name, "type": "STRING", "description": description, "default": value,
            "value": value, "allowedValues": list(allowed), "flag": flag,
            **_ui(group, label, control="DROPDOWN_LIST")}


def _text(name, value, flag, description, group, label):
    return {"name": name, "type": "STRING", "description": description, "default": value,
            "value": value, "minLength": 1, "flag": flag, **_ui(group, label)}


def setting_parameter(name: str, value, group: str, **override) -> dict:
    """The job parameter of option ``name`` (``core.option_table``) holding ``value``: its
    name, type, range, label and description are the table's; ``override`` replaces what a
    farm job says otherwise (a guided ceiling's 0 for none, a flag the template fills)."""
    option = OPTIONS[name]
    description = option.help + "."
    control = {}
    entry = {"name": option.farm, "flag": option.option}
    if option.kind == "bool":
        text = "true" if value else "false"
        entry.update(type="STRING", default=text, value=text, allowedValues=["true", "false"],
                     flag=f"{option.option}-value")
        control = {"control": "CHECK_BOX"}
    elif option.kind == "choice":
        entry.update(type="STRING", default=value, value=value, allowedValues=list(option.values))
        control = {"control": "DROPDOWN_LIST"}
    elif option.none_word is not None:
        text = option.none_word if value is None else f"{value}"
        entry.update(type="STRING", default=text, value=text, minLength=1)
        description += f" {option.none_word.capitalize()}: {option.none_means}."
    else:
        entry.update(type="INT" if option.kind == "int" else "FLOAT", default=value, value=value)
        low = option.low if option.low is not None else option.above
        entry.update({key: bound for key, bound in (("minValue", low), ("maxValue", option.high))
                      if bound is not None})
    entry.update({"description": description, **override})
    return {**entry, **_ui(group, option.label, **control)}


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
    return [setting_parameter(name, getattr(m, name), _MAPS) for name in MAP_OPTIONS]


def _farm_parameters(job: FarmJob) -> list[dict]:
    """Frames per task, the device, the xsl-render command and how a worker gets it."""
    return [
        setting_parameter("frames_per_task", job.frames_per_task, _FARM, flag=None,
                          description=f"{OPTIONS['frames_per_task'].help} (Open Job Description "
                          "spreads the frames evenly over as many tasks as this needs). The tasks' "
                          "timeout was fixed with the bundle for its own value: write the bundle "
                          "again (--frames-per-task) to raise it far."),
        setting_parameter("device", job.device, _FARM,
                          description=f"{OPTIONS['device'].help}. The steps' host requirements (a "
                          "GPU or not) were fixed with the bundle: write it again to change device."),
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
        setting_parameter("max_spp", o.max_spp, render),
        _text("Resolution", f"{width}x{height}", "--resolution", "Render resolution WxH.", render,
              "Resolution"),
        setting_parameter("seed", o.seed, render),
        *_map_parameters(job.map_options),
        *[setting_parameter(name, getattr(o, name), tiles) for name in
          ("min_spp", "tile_size", "tile_quantile", "spp_levels", "margin", "render_cost",
           "adaptive_threshold")],
        setting_parameter("tasks_per_frame", job.tasks_per_frame, _FARM, flag=None),
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
        setting_parameter("time_budget", g.time_budget, render, minValue=MIN_FARM_TIME_BUDGET),
        setting_parameter("importance", g.importance, render),
        # An INT parameter cannot be empty: 0 stands for no ceiling, and a guided ceiling above
        # UNBOUNDED_SPP means none anyway.
        setting_parameter("max_spp", o.max_spp if o.has_ceiling else NO_CEILING, render,
                          minValue=NO_CEILING, maxValue=UNBOUNDED_SPP,
                          description=f"{OPTIONS['max_spp'].help}; {NO_CEILING}: no ceiling."),
        _text("Resolution", f"{width}x{height}", "--resolution", "Render resolution WxH.", render,
              "Resolution"),
        setting_parameter("seed", o.seed, render),
        *[setting_parameter(name, getattr(g, name), render) for name in
          ("pilot_fraction", "exponent", "level_ratio")],
        setting_parameter("tile_size", o.tile_size, render),
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
