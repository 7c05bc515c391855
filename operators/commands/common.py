"""Options several commands share: the scene to open, resolution and frame, map options."""
from __future__ import annotations

import argparse
import sys
import warnings
from contextlib import contextmanager

from ...core.errors import InputError
from ...core.map_options import MapOptions


def add_scene_positional(parser, help_text: str = "the .blend file (never written)") -> None:
    """SCENE.blend, or nothing at all inside Blender (the batch entry), where the scene is
    the one Blender has open (``blender -b scene.blend --python-expr ...``)."""
    if getattr(parser, "in_blender", False):
        parser.add_argument("scene", metavar="SCENE.blend", nargs="?", default=None, type=_no_scene,
                            help="leave out: inside Blender the open file is used")
    else:
        parser.add_argument("scene", metavar="SCENE.blend", help=help_text)


def _no_scene(text: str):
    raise argparse.ArgumentTypeError(f"inside Blender the open file is used; leave out '{text}' "
                                     "(blender -b SCENE.blend --python-expr ... -- COMMAND ...)")


def add_scene_arguments(parser) -> None:
    add_scene_positional(parser)
    parser.add_argument("--scene-name", help="which scene of the file (default: the active one)")
    parser.add_argument("--resolution", metavar="WxH", help="render resolution (default: the scene's)")
    parser.add_argument("--frame", type=int, help="frame to evaluate (default: the current one)")


def parse_resolution(text: str | None) -> tuple[int, int] | None:
    """'512x288' -> (512, 288); None stays None (the scene's own resolution)."""
    from ...core.render_options import parse_resolution as parse

    return None if text is None else parse(text)


def _auto_or(kind):
    def convert(text: str):
        return None if text == "auto" else kind(text)
    convert.__name__ = f"{kind.__name__} or auto"
    return convert


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
    group.add_argument("--light-n", type=_auto_or(int), default=None,
                       help="eq. 6 iterations n, or auto from the fog's optical depth (auto)")
    group.add_argument("--light-sigma-base", type=_auto_or(float), default=None,
                       help="eq. 6 sigma_base in px at 512 px, or auto (auto)")
    group.add_argument("--minbound", action=argparse.BooleanOptionalAction, default=defaults.minbound,
                       help="fill sky pixels with the smallest X (MinBound; on)")


def map_options_from_args(args) -> MapOptions:
    return MapOptions(wx=args.wx, ws=args.ws, xs_op=args.xs_op, wxs=args.wxs, wl=args.wl,
                      xsl_op=args.xsl_op, light_n=args.light_n,
                      light_sigma_base=args.light_sigma_base, minbound=args.minbound).validate()


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
