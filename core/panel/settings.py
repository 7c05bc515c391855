"""The artist panel's settings as plain data: which options of ``core.option_table`` it shows,
as what, and the fog presets; turned into Blender properties by ``addon/panel/properties.py``.

``map_options`` / ``render_options`` / ``guided_options`` turn a scene's values into the
options the command line builds from its arguments, so the panel, scripts and ``xsl-render``
run the same maps and renders. The presets follow section 4.4 of the paper ("values of n
between 4-8 work well for moderately thin media, increasing as high as 20 for thicker media.
For sigma_base, values of up to 4 work well in thin media, increasing as high as 10"); each
keeps XS(0.5, 0.5, +), XSL(0.5, 0.5, +) and MinBound.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..maps.options import MapOptions
from ..option_table import OPTIONS, Option
from ..sampling.guided_plan import GuidedOptions
from ..sampling.render_options import RenderOptions

#: The options the panel shows (and the preferences hold the defaults of), in the order the
#: preferences list them.
PANEL_OPTIONS = ("estimator", "time_budget", "director", "max_spp", "min_spp", "tile_size", "denoise",
                 "importance", "wx", "ws", "xs_op", "wxs", "wl", "xsl_op", "light_auto", "light_n",
                 "light_sigma_base", "minbound")
SETTINGS: tuple[Option, ...] = tuple(OPTIONS[name] for name in PANEL_OPTIONS)
#: The scene properties of those options (``estimator`` is ``volume_estimator`` there).
SETTING_NAMES = tuple(setting.prop or setting.name for setting in SETTINGS)
#: A scene's own switch, saved with the file (not a panel default: a file renders as its
#: artist set it until they turn it on).
AUTO_VOLUMES = OPTIONS["auto_volumes"]


def panel_value(option: Option, value):
    """A value as the panel's property holds it: a choice's identifier in upper case."""
    return value.upper() if option.kind == "choice" and isinstance(value, str) else value


def builtin_defaults() -> dict:
    """Property -> its default in the panel."""
    return {setting.prop or setting.name: panel_value(setting, setting.panel_value) for setting in SETTINGS}


@dataclass(frozen=True)
class Preset:
    label: str
    description: str
    values: dict


_PAPER_COMBINATIONS = {"wx": 0.5, "ws": 0.5, "xs_op": "ADD", "wxs": 0.5, "wl": 0.5, "xsl_op": "ADD",
                       "minbound": True}

PRESETS: dict[str, Preset] = {
    "THIN_FOG": Preset(
        "Thin Fog", "Light haze: n = 6 and sigma_base = 3, the middle of the paper's ranges for "
        "thin media (n 4-8, sigma_base up to 4)",
        {**_PAPER_COMBINATIONS, "light_auto": False, "light_n": 6, "light_sigma_base": 3.0}),
    "THICK_FOG": Preset(
        "Thick Fog", "Dense fog or smoke: n = 16 and sigma_base = 8, between the paper's "
        "thicker-medium example (12, 6) and its upper values (20, 10)",
        {**_PAPER_COMBINATIONS, "light_auto": False, "light_n": 16, "light_sigma_base": 8.0}),
    "NIGHT_ROAD": Preset(
        "Night Road with Lights", "The paper's road scene: XSL with the light map, MinBound for "
        "the sky, and n and sigma_base per lamp from the fog between it and the camera (near "
        "lamps spread little, far ones up to n = 20, sigma_base = 10)",
        {**_PAPER_COMBINATIONS, "director": "XSL", "light_auto": True}),
}


def map_options(settings) -> MapOptions:
    """The MapOptions of a settings object (a scene's ``xsl_render`` or any object with the
    properties of ``SETTING_NAMES``); InputError for an impossible combination."""
    return MapOptions(
        wx=float(settings.wx), ws=float(settings.ws), xs_op=str(settings.xs_op).lower(),
        wxs=float(settings.wxs), wl=float(settings.wl), xsl_op=str(settings.xsl_op).lower(),
        light_n=None if settings.light_auto else int(settings.light_n),
        light_sigma_base=None if settings.light_auto else float(settings.light_sigma_base),
        minbound=bool(settings.minbound)).validate()


def render_options(settings, budget: bool = False) -> RenderOptions:
    """The RenderOptions of a settings object (seed 0, whole tiles' maxima, as the command
    line's defaults); InputError for an impossible combination (e.g. min above max). Min
    Samples only counts for the director map (a time budget's render, ``budget``, has no
    floor)."""
    min_spp = 1 if budget else int(settings.min_spp)
    return RenderOptions(max_spp=int(settings.max_spp), min_spp=min_spp,
                         tile_size=int(settings.tile_size), denoise=bool(settings.denoise),
                         estimator=str(getattr(settings, "volume_estimator", "AUTO")).lower()).check()


def guided_options(settings) -> GuidedOptions:
    """The GuidedOptions of a settings object: its time budget and importance map, the
    command line's defaults for the rest (Max Samples and Tile Size are ``render_options``');
    unchecked (the request that holds them checks them)."""
    return GuidedOptions(time_budget=float(settings.time_budget), importance=str(settings.importance).lower())
