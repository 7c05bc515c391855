"""Every setting a user sets, declared once: name, type, range, default, label and what it does
to the picture. The command line's options (``operators/commands/option_flags.py``), the
panel's properties (``addon/panel/properties.py``) and a farm job's parameters
(``core/farm/job_parameters.py``) are built from :data:`OPTIONS`, and core's options check
their values with :meth:`Option.check`, so a range or a default is written in one place
(``tests/test_option_table.py`` holds the three front ends to it).
"""
from __future__ import annotations

from dataclasses import dataclass

from .checks import MAX_SAMPLES, MAX_SEED, MAX_SIDE, finite_number, whole_number
from .errors import Field, SettingError

#: Smallest tile edge: below it the fixed cost of a Cycles render outweighs the samples saved.
MIN_TILE_SIZE = 8
#: Bounds of the light map's n and sigma_base: the paper uses up to 20 and 10; eq. 6 with n
#: iterations has about n^3 / 3 Gaussians, and a sigma_base of 100 spreads a glow over frames.
MAX_N = 100
MAX_SIGMA_BASE = 100.0
#: The longest time budget accepted: a week (anything longer is a typo).
MAX_TIME_BUDGET = 7 * 24 * 3600.0
#: How two director maps combine (the paper's section 4.3), with what each does.
_OPERATOR_CHOICES = (("add", "Add", "Weighted sum: either map draws samples (the paper's choice)"),
                     ("multiply", "Multiply", "Weighted product: a pixel needs both to draw samples"))
OPERATORS = tuple(choice[0] for choice in _OPERATOR_CHOICES)
#: Director maps a time budget's samples can be weighed by.
IMPORTANCE_MAPS = ("none", "x", "xs", "xsl")
#: Cycles' devices a farm job renders on.
DEVICES = ("CPU", "GPU")
#: Frames one farm task renders in one Blender process (the scene opened and synced once per
#: chunk), and more than a submission means.
DEFAULT_FRAMES_PER_TASK, MAX_FRAMES_PER_TASK = 8, 1000
#: Tile tasks a frame's rectangles are shared among unless asked otherwise, and at most.
DEFAULT_TASKS_PER_FRAME, MAX_GROUPS = 4, 10_000
_CYCLES = " (Cycles' limit)"


@dataclass(frozen=True)
class Option:
    """One setting as every front end shows it.

    ``name`` is the field of core's options it fills (``RenderOptions.max_spp``); ``kind`` is
    "int", "float", "bool" or "choice" (``choices``: value, label, what it does). ``default``
    None means off, automatic or the scene's own, as ``none_means`` says and the command line
    and a farm job write ``none_word``; the panel, which shows a number, starts from
    ``panel_default`` then. ``low``/``high`` bound a value inclusively, ``above``
    exclusively; ``soft_low``/``soft_high`` are the panel slider's. ``flag``, ``prop`` and
    ``farm`` name its command-line option, panel property and job parameter (None: that
    front end does not take it; ``flag`` and ``prop`` default to the name).
    """

    name: str
    kind: str
    default: object
    label: str
    help: str
    low: float | None = None
    high: float | None = None
    above: float | None = None
    limit: str = ""
    choices: tuple = ()
    none_word: str | None = None
    none_means: str = ""
    panel_default: object = None
    soft_low: float | None = None
    soft_high: float | None = None
    flag: str | None = ""
    prop: str | None = None
    farm: str | None = None

    @property
    def option(self) -> str | None:
        """The command-line option (``--max-spp``), or None."""
        if self.flag is None:
            return None
        return self.flag or "--" + self.name.replace("_", "-")

    @property
    def values(self) -> tuple:
        """The values of a choice."""
        return tuple(choice[0] for choice in self.choices)

    @property
    def panel_value(self):
        """The panel property's default."""
        return self.default if self.panel_default is None else self.panel_default

    def check(self, value, field: bool = True):
        """``value`` (or its text) checked against the range; SettingError naming the field
        (``field``) or plain words (for argparse, which names the option itself)."""
        name = Field(self.name) if field else None
        if value is None or (self.none_word is not None and value == self.none_word):
            if self.default is None:
                return None
            raise SettingError(f"{{{self.name}.name}} needs a value", **{self.name: value})
        if self.kind == "int":
            low = self.low if self.low is not None else -2 ** 31
            high = self.high if self.high is not None else 2 ** 31 - 1
            return whole_number(value, int(low), int(high), name, self.limit)
        if self.kind == "float":
            return finite_number(value, self.low, self.high, above=self.above, name=name)
        if self.kind == "bool":
            if isinstance(value, bool):
                return value
            raise SettingError(f"{{{self.name}.name}} must be true or false (got {{{self.name}.value}})",
                               **{self.name: value})
        if value not in self.values:
            raise SettingError(f"{{{self.name}.name}} must be one of {', '.join(self.values)} "
                               f"(got '{{{self.name}.value}}')", **{self.name: value})
        return value


def _choices(*items) -> tuple:
    return tuple(items)


OPTIONS: dict[str, Option] = {option.name: option for option in (
    # -- what auto chooses ----------------------------------------------------------------
    Option("auto_volumes", "bool", False, "Auto Volumes",
           "Render fog, smoke and clouds faster at the same look: every final render of this "
           "scene (F12, animations, command line and farm renders with this extension) picks how "
           "Cycles steps through each volume for that shot, and your own settings come back "
           "afterwards", flag=None),
    Option("estimator", "choice", "auto", "Volumes",
           "How fog, smoke and clouds are rendered: auto picks the fastest way that looks the "
           "same for this shot, scene keeps the file's own Volumes settings",
           choices=_choices(
               ("auto", "Auto", "Fastest at the same look: ray marching at the largest step whose "
                "error hides in the render's noise, the file's settings where it would show"),
               ("scene", "Scene", "The file's own settings (Render Properties › Volumes)"),
               ("unbiased", "Unbiased", "Null scattering, Blender's default: exact, slower in "
                "detailed fog"),
               ("biased", "Biased", "Ray marching at the scene's step rate: faster, but detailed "
                "media can come out lighter or darker")),
           prop="volume_estimator", farm="Estimator"),
    Option("step_rate", "float", None, "Step Rate",
           "biased: Cycles' volume step rate (larger is coarser, faster and less exact); auto: "
           "the coarsest rate it may choose", low=0.01, high=100.0, none_word=None,
           none_means="the scene's"),
    # -- samples and the frame ------------------------------------------------------------
    Option("max_spp", "int", None, "Max Samples",
           "Samples per pixel where the director map is 1 (every pixel of the gold standard); "
           "with a time budget, the most any pixel may get", low=1, high=MAX_SAMPLES,
           limit=_CYCLES, none_means="the scene's own samples", panel_default=64,
           soft_high=4096, farm="MaxSpp"),
    Option("min_spp", "int", 1, "Min Samples",
           "Samples every pixel gets however little the director map asks for: raise it where "
           "dark areas stay noisy", low=1, high=MAX_SAMPLES, limit=_CYCLES, soft_high=64,
           farm="MinSpp"),
    Option("seed", "int", 0, "Seed", "Cycles' seed of every render (another seed, other noise)",
           low=0, high=MAX_SEED, limit=_CYCLES, farm="Seed"),
    Option("denoise", "bool", True, "Denoise",
           "Denoise every finished frame with Open Image Denoise, guided by albedo and normal "
           "(the tiles are never denoised one by one, which would seam)", farm=None),
    # -- tiles of a selective render --------------------------------------------------------
    Option("tile_size", "int", 32, "Tile Size",
           "Edge of the square tiles a selective render is planned on, in pixels (split down to "
           "8 where that pays): smaller follows the map more closely, at more renders",
           low=MIN_TILE_SIZE, high=MAX_SIDE, soft_high=256, farm="TileSize"),
    Option("tile_quantile", "float", 1.0, "Tile Quantile",
           "Which quantile of a tile's per-pixel targets the tile renders with; 1, the maximum, "
           "never gives a pixel fewer samples than the map asks for", above=0.0, high=1.0,
           farm="TileQuantile"),
    Option("spp_levels", "int", 0, "Sample Levels",
           "Round tile samples up to this many geometric levels so that more tiles share a count "
           "and merge into fewer renders (0: off)", low=0, high=1024, farm="SppLevels"),
    Option("margin", "int", 0, "Margin",
           "Pixels rendered around each rectangle and cropped (10: bit-identical to a full-frame "
           "render)", low=0, high=64, farm="Margin"),
    Option("render_cost", "int", 1024, "Render Cost",
           "The fixed cost of one render in pixel-samples: tiles are split down to 8 px where "
           "that saves more", low=0, high=10 ** 15, farm="RenderCost"),
    Option("adaptive_threshold", "float", None, "Adaptive Threshold",
           "Cycles' adaptive sampling inside each rectangle, noise threshold T / sqrt(spp / "
           "max-spp)", above=0.0, high=1.0, none_word="off", none_means="off",
           farm="AdaptiveThreshold"),
    # -- the paper's director maps ---------------------------------------------------------
    Option("director", "choice", "xsl", "Director Map",
           "Which of the paper's maps spends the samples",
           choices=_choices(("xsl", "XSL", "Fog, saliency and the glow of lights (section 4.5): "
                             "scenes with visible lights"),
                            ("xs", "XS", "Fog and saliency (section 4.3): enough without visible "
                             "lights")), flag=None),
    Option("wx", "float", 0.5, "Fog Weight (w_x)",
           "How much the fog's transmittance (the X map) steers samples: higher gives clear "
           "areas more samples and dense fog fewer", low=0.0, high=10.0, soft_high=1.0, farm="Wx"),
    Option("ws", "float", 0.5, "Saliency Weight (w_s)",
           "How much eye-catching detail (the S map) draws samples", low=0.0, high=10.0,
           soft_high=1.0, farm="Ws"),
    Option("xs_op", "choice", "add", "Fog and Saliency (XS operator)",
           "How the fog and saliency maps combine into XS", choices=_OPERATOR_CHOICES, farm="XsOp"),
    Option("wxs", "float", 0.5, "Fog and Saliency Weight (w_xs)",
           "How much the XS map steers the samples of XSL", low=0.0, high=10.0, soft_high=1.0,
           farm="Wxs"),
    Option("wl", "float", 0.5, "Light Glow Weight (w_l)",
           "How much the glow around visible lights (the L map) draws samples", low=0.0,
           high=10.0, soft_high=1.0, farm="Wl"),
    Option("xsl_op", "choice", "add", "With Light Glow (XSL operator)",
           "How XS and the light map combine into XSL", choices=_OPERATOR_CHOICES, farm="XslOp"),
    Option("light_auto", "bool", True, "Glow per Light (auto n, sigma_base)",
           "Size each light's glow from the fog between it and the camera, on the paper's "
           "ranges (n 4-20, sigma_base 1-10)", flag=None),
    Option("light_n", "int", None, "Glow Spread (n)",
           "How far the glow around each light spreads, in blur iterations of eq. 6: 4-8 for "
           "thin fog, up to 20 for thick", low=0, high=MAX_N, none_word="auto",
           none_means="auto, from the fog's optical depth", panel_default=8, soft_high=20,
           farm="LightN"),
    Option("light_sigma_base", "float", None, "Glow Blur (sigma_base)",
           "The width of the glow's first blur, in pixels at 512 px: up to 4 for thin fog, 10 "
           "for thick", above=0.0, high=MAX_SIGMA_BASE, none_word="auto",
           none_means="auto, from the fog's optical depth", panel_default=4.0, soft_low=0.5,
           soft_high=10.0, farm="LightSigmaBase"),
    Option("minbound", "bool", True, "Fog over Sky (MinBound)",
           "Give the sky the thinnest fog's share of samples, so that fog in front of it is not "
           "left noisy (section 4.1)", farm="MinBound"),
    # -- a time budget ---------------------------------------------------------------------
    Option("time_budget", "float", None, "Time Budget",
           "Seconds each frame may take, everything included (maps, scene sync, samples, "
           "denoising): more seconds, less noise", above=0.0, high=MAX_TIME_BUDGET,
           none_means="none", panel_default=30.0, soft_low=1.0, soft_high=600.0,
           farm="TimeBudget"),
    Option("importance", "choice", "none", "Weighted By (director map)",
           "A director map that weighs where a time budget's samples go (computed inside the "
           "budget); none spreads them evenly",
           choices=_choices(("none", "None", "Every pixel alike"),
                            ("x", "X", "More where the fog is thin (the X map)"),
                            ("xs", "XS", "The fog and saliency (the XS map)"),
                            ("xsl", "XSL", "Also the glow of lights (the XSL map)")), farm="Importance"),
    Option("pilot_fraction", "float", 0.05, "Pilot Fraction",
           "The most of the budget a scoring pilot pass takes (0.02 at most when nothing is "
           "scored)", above=0.0, high=1.0, farm="PilotFraction"),
    Option("exponent", "float", 0.0, "Allocation Exponent",
           "Samples go as the pilot's error score to this power (times the importance map's); "
           "0 scores nothing", low=0.0, high=2.0, flag="--guided-exponent", farm="GuidedExponent"),
    Option("level_ratio", "float", 1.5, "Level Ratio",
           "Sample counts are rounded to powers of this ratio", above=1.0, high=4.0,
           farm="LevelRatio"),
    # -- a farm job ------------------------------------------------------------------------
    Option("frames_per_task", "int", DEFAULT_FRAMES_PER_TASK, "Frames per Task",
           "Frames each task renders in one Blender process, the scene synced once for all",
           low=1, high=MAX_FRAMES_PER_TASK, farm="FramesPerTask"),
    Option("tasks_per_frame", "int", None, "Tile Tasks per Frame",
           "xs, xsl: tile tasks a frame's rectangles are shared among, at about equal cost",
           low=1, high=MAX_GROUPS, none_means=str(DEFAULT_TASKS_PER_FRAME), farm="TasksPerFrame"),
    Option("device", "choice", None, "Cycles Device",
           "The device every render of the job uses", none_means="the scene's",
           choices=_choices(("CPU", "CPU", "The processor"), ("GPU", "GPU", "A GPU Cycles finds")),
           farm="Device"),
)}
#: The paper's map options (``core.maps.options.MapOptions``), in the order front ends list them.
MAP_OPTIONS = ("wx", "ws", "xs_op", "wxs", "wl", "xsl_op", "light_n", "light_sigma_base", "minbound")
#: Every option's default, for the dataclasses that hold the values.
DEFAULTS = {name: option.default for name, option in OPTIONS.items()}


def checked(**values) -> None:
    """Each ``name=value`` checked against its option (SettingError naming the first bad one)."""
    for name, value in values.items():
        OPTIONS[name].check(value)
