"""The artist panel's settings as plain data: names, limits, defaults and the fog presets.

``addon/panel/properties.py`` turns ``SETTINGS`` into Blender properties (on every scene and in
the extension's preferences, which hold the defaults); ``map_options`` / ``render_options`` /
``guided_options`` turn a scene's values into the options the command line builds from its
arguments, so the panel, scripts and ``xsl-render`` run the same maps and renders. The
sampler is the paper's (a director map scales Max Samples) or the guided render within a
time budget (``xsl-render render --mode guided``), with Max Samples as its ceiling.

Presets follow section 4.4 of the paper: "a very thick medium will need a higher value for
n and a medium-high value for sigma_base ... values of n between 4-8 work well for
moderately thin media, increasing as high as 20 for thicker media. For sigma_base, values of
up to 4 work well in thin media, increasing as high as 10 as the medium thickens" (its
road-scene examples: n = 8, sigma_base = 4 for a thin medium, n = 12, sigma_base = 6 for a
thicker one). Every preset keeps the paper's combinations XS(0.5, 0.5, +) and
XSL(0.5, 0.5, +) and MinBound.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..maps.options import MapOptions
from ..sampling.guided_plan import MAX_TIME_BUDGET, GuidedOptions
from ..sampling.render_options import MIN_TILE_SIZE, RenderOptions

#: Cycles' own ceiling for samples per pixel.
CYCLES_MAX_SAMPLES = 1 << 24
OPERATOR_ITEMS = (("ADD", "Add", "Weighted sum: every weighted feature is kept (the paper's choice)"),
                  ("MULTIPLY", "Multiply", "Weighted product A^wa B^wb: one map modulates the other"))
DIRECTOR_ITEMS = (("XSL", "XSL", "X, saliency and the light map (section 4.5): scenes with visible lights"),
                  ("XS", "XS", "X and saliency (section 4.3): enough without visible lights"))
SAMPLER_ITEMS = (("DIRECTOR", "Director Map",
                  "The paper: the XS or XSL map scales Max Samples per pixel"),
                 ("BUDGET", "Time Budget",
                  "Guided: a pilot pass over the frame, then the rest of the time budget where the "
                  "denoised frame keeps its error (optionally weighted by a director map)"))
IMPORTANCE_ITEMS = (("NONE", "None", "Weigh every tile's estimated error alike"),
                    ("X", "X", "Weigh the error by the extinction (X) map: less where the medium hides"),
                    ("XS", "XS", "Weigh the error by the XS map (extinction and saliency)"),
                    ("XSL", "XSL", "Weigh the error by the XSL map (also the glow of lights)"))
ESTIMATOR_ITEMS = (("SCENE", "Scene", "The scene's own volume settings (Render > Volumes)"),
                   ("AUTO", "Auto", "Ray marching at the largest step whose bias, predicted from "
                    "the media, hides in the render's noise; null scattering where it would show"),
                   ("UNBIASED", "Unbiased", "Null scattering, Blender's default"),
                   ("BIASED", "Biased", "Ray marching at the scene's step rate"))
#: The sampler whose settings are the guided render's (``guided_options``).
BUDGET_SAMPLER = "BUDGET"


@dataclass(frozen=True)
class Setting:
    """One setting of the panel: a Blender property built from plain values."""

    name: str
    kind: str                      # "float", "int", "bool" or "enum"
    label: str
    description: str
    default: object
    min: float | None = None
    max: float | None = None
    soft_min: float | None = None
    soft_max: float | None = None
    items: tuple = field(default=())


SETTINGS: tuple[Setting, ...] = (
    Setting("sampler", "enum", "Sampler", "How the render spends its samples", "DIRECTOR",
            items=SAMPLER_ITEMS),
    Setting("director", "enum", "Director Map",
            "Which combined map spends the samples", "XSL", items=DIRECTOR_ITEMS),
    Setting("time_budget", "float", "Time Budget",
            "Seconds for the whole guided render of a frame: importance map, scene sync, passes "
            "and denoising (each frame of an animation gets its own)", 30.0,
            min=0.1, max=MAX_TIME_BUDGET, soft_min=1.0, soft_max=600.0),
    Setting("importance", "enum", "Importance",
            "Director map that weighs the guided render's estimated error (computed inside the "
            "budget)", "NONE", items=IMPORTANCE_ITEMS),
    Setting("wx", "float", "X Weight", "w_x: weight of the extinction (X) map in XS (section 4.3)",
            0.5, min=0.0, max=10.0, soft_max=1.0),
    Setting("ws", "float", "S Weight", "w_s: weight of the saliency (S) map in XS (section 4.3)",
            0.5, min=0.0, max=10.0, soft_max=1.0),
    Setting("xs_op", "enum", "XS Operator", "How X and S are combined into XS", "ADD",
            items=OPERATOR_ITEMS),
    Setting("wxs", "float", "XS Weight", "w_xs: weight of the XS map in XSL (section 4.5)",
            0.5, min=0.0, max=10.0, soft_max=1.0),
    Setting("wl", "float", "L Weight", "w_l: weight of the light (L) map in XSL (section 4.5)",
            0.5, min=0.0, max=10.0, soft_max=1.0),
    Setting("xsl_op", "enum", "XSL Operator", "How XS and L are combined into XSL", "ADD",
            items=OPERATOR_ITEMS),
    Setting("light_auto", "bool", "Auto Light Spread",
            "Derive n and sigma_base for each light from the optical depth of the medium between "
            "the camera and the light, on the paper's ranges (n 4-20, sigma_base 1-10)", True),
    Setting("light_n", "int", "Iterations (n)",
            "n of eq. 6: how many times the 0-LightMap is spread (4-8 thin media, up to 20 thick)",
            8, min=0, max=40, soft_max=20),
    Setting("light_sigma_base", "float", "Sigma Base",
            "sigma_base of eq. 6 in pixels at 512 px on the longer side (up to 4 thin media, up "
            "to 10 thick)", 4.0, min=0.05, max=64.0, soft_min=0.5, soft_max=10.0),
    Setting("minbound", "bool", "MinBound",
            "Give sky pixels the smallest X of the frame, so that fog in front of the sky is "
            "not starved of samples (section 4.1)", True),
    Setting("max_spp", "int", "Max Samples",
            "Samples per pixel where the director map is 1 (the gold standard's count); with the "
            "Time Budget sampler, the most samples any pixel may get (the guided ceiling)", 64,
            min=1, max=CYCLES_MAX_SAMPLES, soft_max=4096),
    Setting("min_spp", "int", "Min Samples",
            "Samples every pixel gets at least, however low the director map (Director Map "
            "sampler only)", 1,
            min=1, max=CYCLES_MAX_SAMPLES, soft_max=64),
    Setting("tile_size", "int", "Tile Size",
            "Edge of the square tiles the render plan starts from (split down to 8 px where it pays)",
            32, min=MIN_TILE_SIZE, max=4096, soft_max=256),
    Setting("volume_estimator", "enum", "Volume Estimator",
            "How Cycles estimates the fog and smoke of this render (the scene keeps its own "
            "settings)", "AUTO", items=ESTIMATOR_ITEMS),
    Setting("denoise", "bool", "Denoise",
            "Denoise every finished frame (gold and selective alike) with Open Image Denoise, "
            "guided by albedo and normal; the tiles themselves are never denoised one by one",
            True),
)
SETTING_NAMES = tuple(setting.name for setting in SETTINGS)
#: A scene's own switch, saved with the file (not a panel default: a file renders as its
#: artist set it until they turn it on).
AUTO_VOLUMES = Setting(
    "auto_volumes", "bool", "Auto Volumes",
    "Render fog, smoke and clouds faster at the same look: every final render of this scene "
    "(F12, animations, command line and farm renders with this extension) picks how Cycles "
    "steps through each volume for that shot, and your own settings come back afterwards",
    False)


def builtin_defaults() -> dict:
    return {setting.name: setting.default for setting in SETTINGS}


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
    attributes of ``SETTINGS``); InputError for an impossible combination."""
    return MapOptions(
        wx=float(settings.wx), ws=float(settings.ws), xs_op=str(settings.xs_op).lower(),
        wxs=float(settings.wxs), wl=float(settings.wl), xsl_op=str(settings.xsl_op).lower(),
        light_n=None if settings.light_auto else int(settings.light_n),
        light_sigma_base=None if settings.light_auto else float(settings.light_sigma_base),
        minbound=bool(settings.minbound)).validate()


def uses_budget(settings) -> bool:
    """True when the settings ask for the guided render within a time budget."""
    return settings.sampler == BUDGET_SAMPLER


def render_options(settings) -> RenderOptions:
    """The RenderOptions of a settings object (seed 0, whole tiles' maxima, as the command
    line's defaults); InputError for an impossible combination (e.g. min above max). Min
    Samples only counts for the director-map sampler (the guided render has no floor)."""
    min_spp = 1 if uses_budget(settings) else int(settings.min_spp)
    return RenderOptions(max_spp=int(settings.max_spp), min_spp=min_spp,
                         tile_size=int(settings.tile_size), denoise=bool(settings.denoise),
                         estimator=str(getattr(settings, "volume_estimator", "AUTO")).lower()).check()


def guided_options(settings) -> GuidedOptions:
    """The GuidedOptions of a settings object: its time budget and importance map, the
    command line's defaults for the rest (Max Samples and Tile Size are ``render_options``');
    InputError for an impossible value (a budget that is not a positive number of seconds,
    or more than a week)."""
    return GuidedOptions(time_budget=float(settings.time_budget),
                         importance=str(settings.importance).lower()).check()
