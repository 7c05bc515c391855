"""Options several commands share, as flags: the scene to open, resolution and frame, map
options, tile options, the estimator, guided's budget. (What they become, checked:
``options_from_args.py``.)"""
from __future__ import annotations

import argparse
import sys
import warnings
from contextlib import contextmanager

from ...core.checks import MAX_SIDE
from ...core.maps.options import MAX_N, MAX_SIGMA_BASE, MapOptions
from ...core.sampling.render_options import MIN_TILE_SIZE
from . import argtypes


def add_scene_positional(parser, help_text: str = "the .blend file (never written)") -> None:
    """SCENE.blend, or nothing at all inside Blender (the batch entry), where the scene is
    the one Blender has open (``blender -b scene.blend --python-expr ...``)."""
    if getattr(parser, "in_blender", False):
        parser.add_argument("scene", metavar="SCENE.blend", nargs="?", default=None, type=_no_scene,
                            help="leave out: inside Blender the open file is used")
    else:
        parser.add_argument("scene", metavar="SCENE.blend", type=argtypes.SCENE, help=help_text)


def _no_scene(text: str):
    raise argparse.ArgumentTypeError(f"inside Blender the open file is used; leave out '{text}' "
                                     "(blender -b SCENE.blend --python-expr ... -- COMMAND ...)")


def add_scene_arguments(parser) -> None:
    add_scene_positional(parser)
    parser.add_argument("--scene-name", help="which scene of the file (default: the active one)")
    parser.add_argument("--resolution", metavar="WxH", type=argtypes.RESOLUTION,
                        help="render resolution (default: the scene's)")
    parser.add_argument("--frame", type=argtypes.FRAME, help="frame to evaluate (default: the current one)")


def parse_resolution(text: str | None) -> tuple[int, int] | None:
    """'512x288' -> (512, 288); None stays None (the scene's own resolution)."""
    from ...core.sampling.render_options import parse_resolution as parse

    return None if text is None else parse(text)


def add_map_arguments(parser) -> None:
    """The paper's map options (DESIGN.md): XS and XSL weights and operators, L's n and
    sigma_base (or auto), MinBound."""
    group = parser.add_argument_group("director maps (the paper's names)")
    defaults = MapOptions()
    group.add_argument("--wx", type=float, default=defaults.wx, help="weight of X in XS (0.5)")
    group.add_argument("--ws", type=float, default=defaults.ws, help="weight of S in XS (0.5)")
    group.add_argument("--xs-op", default=defaults.xs_op, help="XS operator: add or multiply (add)")
    group.add_argument("--wxs", type=float, default=defaults.wxs, help="weight of XS in XSL (0.5)")
    group.add_argument("--wl", type=float, default=defaults.wl, help="weight of L in XSL (0.5)")
    group.add_argument("--xsl-op", default=defaults.xsl_op, help="XSL operator: add or multiply (add)")
    group.add_argument("--light-n", type=argtypes.auto_or(argtypes.integer(0, MAX_N)), default=None,
                       help="eq. 6 iterations n, or auto from the fog's optical depth (auto)")
    group.add_argument("--light-sigma-base", default=None,
                       type=argtypes.auto_or(argtypes.number(above=0.0, hi=MAX_SIGMA_BASE)),
                       help="eq. 6 sigma_base in px at 512 px, or auto (auto)")
    group.add_argument("--minbound", action=argparse.BooleanOptionalAction, default=defaults.minbound,
                       help="fill sky pixels with the smallest X (MinBound; on)")


def add_tile_arguments(parser) -> None:
    """How a selective render cuts the frame into rectangles
    (``core.sampling.render_options.RenderOptions``)."""
    tiles = parser.add_argument_group("tiles (xs, xsl)")
    tiles.add_argument("--min-spp", type=argtypes.SAMPLES, default=1,
                       help="samples floor per pixel (default 1)")
    tiles.add_argument("--tile-size", type=argtypes.integer(MIN_TILE_SIZE, MAX_SIDE), default=32,
                       help="tile edge in pixels (default 32)")
    tiles.add_argument("--tile-quantile", type=argtypes.number(above=0.0, hi=1.0), default=1.0,
                       help="quantile of a tile's per-pixel targets it renders with (default 1 = max)")
    tiles.add_argument("--spp-levels", type=argtypes.integer(0, 1024), default=0,
                       help="round tile samples up to N geometric levels (default 0 = off)")
    tiles.add_argument("--margin", type=argtypes.integer(0, 64), default=0,
                       help="pixels rendered around each rectangle and cropped (default 0; "
                            "10 = bit-identical to a full-frame render)")
    tiles.add_argument("--render-cost", type=argtypes.integer(0, 10**15), default=1024,
                       help="fixed cost of one render in pixel-samples; tiles split down to 8 px "
                            "where that saves more (default 1024)")
    tiles.add_argument("--adaptive-threshold", default=None,
                       type=argtypes.auto_or(argtypes.number(above=0.0, hi=1.0), "off"),
                       help="Cycles adaptive sampling inside each rectangle, noise threshold "
                            "T / sqrt(spp / max-spp) (default: off)")
    parser.add_argument("--seed", type=argtypes.SEED, default=0, help="Cycles seed for every render (default 0)")
    parser.add_argument("--denoise", action=argparse.BooleanOptionalAction, default=True,
                        help="denoise the finished frame with Open Image Denoise, guided by albedo "
                             "and normal, the same in every mode (default on)")


def add_estimator_arguments(parser) -> None:
    """How Cycles estimates the volumes (``core.sampling.volume_estimator``)."""
    from ...core.sampling.volume_estimator import ESTIMATORS, MAX_STEP_RATE, MIN_STEP_RATE

    group = parser.add_argument_group("volume estimator")
    group.add_argument("--estimator", choices=ESTIMATORS, default=None,
                       help="scene: the scene's own volume settings (the default of every mode "
                            "but guided); unbiased: null scattering; biased: ray marching; auto "
                            "(guided's default): ray marching at the largest step rate whose "
                            "predicted bias hides in the run's noise, else null scattering")
    group.add_argument("--step-rate", type=argtypes.number(MIN_STEP_RATE, MAX_STEP_RATE), default=None,
                       metavar="RATE",
                       help="biased: Cycles' volume step rate (default: the scene's); auto: the "
                            "largest rate it may choose")


def add_guided_arguments(parser, budget_required: bool = False) -> None:
    """The options of ``--mode guided`` (``core.sampling.guided_plan.GuidedOptions``);
    ``budget_required`` where there is no other mode."""
    from ...core.sampling.guided_plan import IMPORTANCE_MAPS, MAX_TIME_BUDGET, GuidedOptions

    # The ranges of GuidedOptions.check, here so that a bad value ends the command while it is
    # parsed (one line, before Blender loads) whatever the mode.
    defaults = GuidedOptions(time_budget=1.0)
    guided = parser.add_argument_group("guided")
    guided.add_argument("--time-budget", type=argtypes.number(above=0.0, hi=MAX_TIME_BUDGET), metavar="SECONDS",
                        required=budget_required,
                        help="guided: seconds for the whole render (maps, passes, denoising)")
    guided.add_argument("--importance", choices=IMPORTANCE_MAPS, default=defaults.importance,
                        help="guided: director map that weighs the samples (default none)")
    guided.add_argument("--pilot-fraction", type=argtypes.number(above=0.0, hi=1.0),
                        default=defaults.pilot_fraction,
                        help="guided: most of the budget a scoring pilot pass takes (default "
                             f"{defaults.pilot_fraction}; 0.02 at most when nothing is scored)")
    guided.add_argument("--guided-exponent", type=argtypes.number(0.0, 2.0), default=defaults.exponent,
                        help="guided: samples go as the pilot's error score to this power "
                             f"(times the importance map's); 0 scores nothing (default {defaults.exponent})")
    guided.add_argument("--level-ratio", type=argtypes.number(above=1.0, hi=4.0), default=defaults.level_ratio,
                        help="guided: sample counts are rounded to powers of this ratio "
                             f"(default {defaults.level_ratio})")


@contextmanager
def warnings_as_lines(*categories):
    """Collect warnings of the given kinds and print each once as a one-line warning."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    seen = dict.fromkeys(str(w.message) for w in caught
                         if not categories or issubclass(w.category, categories))
    for message in seen:
        print(f"xsl-render: warning: {message}", file=sys.stderr)
