"""Options several commands share, as flags: the scene to open, resolution and frame, map
options, tile options, the estimator, a time budget; the settings among them are built from
core's option table (``option_flags.py``). What they become, checked: ``options_from_args.py``."""
from __future__ import annotations

import argparse
import sys
import warnings
from contextlib import contextmanager

from ...core.option_table import MAP_OPTIONS
from . import argtypes
from .option_flags import add_option


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
    """The paper's map options (``core.maps.options.MapOptions``): XS and XSL weights and
    operators, L's n and sigma_base (or auto), MinBound."""
    group = parser.add_argument_group("director maps (the paper's names)")
    for name in MAP_OPTIONS:
        add_option(group, name)


def add_tile_arguments(parser, group=None) -> None:
    """How a selective render cuts the frame into rectangles
    (``core.sampling.render_options.RenderOptions``), and (in ``group``, else the parser's
    own options) the seed and denoising of every mode."""
    tiles = parser.add_argument_group("tiles (xs, xsl)")
    for name in ("min_spp", "tile_size", "tile_quantile", "spp_levels", "margin", "render_cost",
                 "adaptive_threshold"):
        add_option(tiles, name)
    add_option(group or parser, "seed")
    add_option(group or parser, "denoise")


def add_guided_arguments(parser, budget_required: bool = False) -> None:
    """The options of a time budget (``core.sampling.guided_plan.GuidedOptions``);
    ``budget_required`` where there is no other mode."""
    guided = parser.add_argument_group("time budget (guided)")
    add_option(guided, "time_budget", metavar="SECONDS", required=budget_required)
    for name in ("importance", "pilot_fraction", "exponent", "level_ratio"):
        add_option(guided, name)


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
