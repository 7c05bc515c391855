"""``xsl-render experiment``: the paper's objective validation (Fig. 8, Tables I and II) on the
example scenes, with FLIP, equal-time baselines and a uniform curve, every run measured against
the converged reference (cached, ``xsl-render reference``) as well as, the paper's measure,
against the gold standard, into DIR/results.json and DIR/report.html.

Resumable: every finished map set, render and comparison is kept with the hash of its inputs
and reused, so rerunning after Ctrl-C (or a crash) continues where it stopped.
"""
from __future__ import annotations

import argparse
from pathlib import Path

NAME = "experiment"
#: Finished steps are kept as they come (the run resumes), not held back for the end.
OUTPUTS_AS_A_SET = False
HELP = ("render gold, X-only, S-only, XS, XSL, uniform and equal-time baselines of the example "
        "scenes, measure time, MSE, VDP and FLIP against the converged reference (and the paper's "
        "gold standard), and write results.json and an HTML report (resumable)")


def add_arguments(parser) -> None:
    from ...core.validation.plan import DEFAULT_MINBOUND_SCENES, VARIANTS
    from . import argtypes

    parser.add_argument("--scenes", metavar="LIST",
                        help="comma-separated example names (balls_a, balls_b, statue, road; "
                             "street, the animation, renders its current frame) or "
                             ".blend paths (default: the paper's four examples)")
    parser.add_argument("--out", default="xsl-experiment", metavar="DIR", type=argtypes.output_folder(),
                        help="output folder; finished work in it is reused (default xsl-experiment)")
    add_run_arguments(parser)
    parser.add_argument("--variants", metavar="LIST",
                        help=f"runs per scene (default all but xsl_no_minbound): {', '.join(VARIANTS)}; "
                             "gold is always rendered")
    parser.add_argument("--minbound-scenes", metavar="LIST", default=",".join(DEFAULT_MINBOUND_SCENES),
                        help="scenes that also render XSL without MinBound (default road)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def add_run_arguments(parser) -> None:
    """Ceiling, size, tiles, seed, denoising, VDP."""
    from . import argtypes
    from .option_flags import add_option

    add_option(parser, "max_spp", default=16,
               help="samples per pixel of the gold standard and ceiling of the maps (the paper's 16)")
    parser.add_argument("--resolution", metavar="WxH", type=argtypes.RESOLUTION,
                        help="render every scene at this size")
    parser.add_argument("--size", type=argtypes.integer(8, 16384), metavar="N",
                        help="scale each scene to N pixels on its longer side (the paper: 512; "
                             "default: each scene's own resolution)")
    for name in ("min_spp", "tile_size", "seed"):
        add_option(parser, name)
    add_quality_arguments(parser, "samples of the converged reference each run is measured "
                                  "against (default max(1024, 16 x the ceiling); cached)")


def add_quality_arguments(parser, reference_help: str | None = None) -> None:
    """--denoise, --vdp and --reference-spp, shared with ``demo`` (which hides the last)."""
    from . import argtypes
    from .option_flags import add_option

    parser.add_argument("--reference-spp", type=argtypes.SAMPLES, metavar="N",
                        help=reference_help or argparse.SUPPRESS)
    add_option(parser, "denoise", help="denoise every finished frame with Open Image Denoise, every "
                                       "run alike (off compares the raw path-traced frames)")
    parser.add_argument("--vdp", action=argparse.BooleanOptionalAction, default=True,
                        help="run ColorVideoVDP when it is installed (default on; it is slow)")


def settings_from_args(args, variants=None):
    from ...core.validation.plan import ValidationSettings, parse_variants
    from .common import parse_resolution

    if args.resolution and args.size:
        from ...core.errors import InputError

        raise InputError("give --resolution or --size, not both")
    settings = ValidationSettings(
        max_spp=args.max_spp, resolution=parse_resolution(args.resolution),
        longest_side=args.size, min_spp=args.min_spp, tile_size=args.tile_size, seed=args.seed,
        vdp=args.vdp, denoise=args.denoise, reference_spp=args.reference_spp,
        variants=variants or parse_variants(getattr(args, "variants", None)))
    settings.render_options()       # InputError for impossible options, before any work
    return settings


def run_and_report(jobs, settings, out: Path, label: str, quiet: bool) -> dict:
    """Run the validation with a progress bar and Ctrl-C handling, then write the report.
    Prints one line per scene and, last, the report's path."""
    import sys

    from ...addon.validation.runner import run_validation
    from ...core.validation.report_html import write_report
    from ..interrupt import InterruptToCancel
    from ..progress_bar import ProgressBar

    bar = None if quiet else ProgressBar(label)
    try:
        with InterruptToCancel() as interrupt:
            results = run_validation(jobs, settings, out, progress=interrupt.wrap(bar))
            if bar is not None:
                bar(1.0, "writing the report")
            report = write_report(results, out)
    finally:
        if bar is not None:
            bar.close()
    for name, scene in results["scenes"].items():
        for warning in scene["warnings"]:
            print(f"xsl-render: warning: {name}: {warning}", file=sys.stderr)
        print("\n".join(scene_lines(name, scene)))
    if not results["vdp"]["ran"]:
        print(f"VDP skipped: {results['vdp']['skipped']}")
    print(f"{results['rendered']} step(s) computed, {results['reused']} reused; "
          f"results in {out / 'results.json'}")
    print(f"report: {report.resolve()}")
    return results


def scene_lines(name: str, scene: dict) -> list[str]:
    """The scene's runs against the converged reference: time, samples, FLIP, MSE and, where
    the uniform runs make a curve, the equal-quality speedup over uniform (never a time ratio
    to gold without equal quality)."""
    from ...core.validation.curves_results import metric_values, speedup_text
    from ...core.validation.report_reference import reference_description

    size = scene["size"]
    lines = [f"{name} ({size[0]}x{size[1]}, ceiling {scene['max_spp']} spp) against "
             f"{reference_description(scene)}:",
             f"  {'run':<30} {'time':>8} {'spp':>6} {'FLIP':>7} {'MSE':>9}   equal quality vs uniform (FLIP, MSE)"]
    for run_name, run in scene["runs"].items():
        values = metric_values(run.get("reference_metrics", {}))
        flip = "-" if values["flip"] is None else f"{values['flip']:.4f}"
        mse = "-" if values["mse"] is None else f"{values['mse']:.2e}"
        speedups = run.get("equal_quality")
        if run["kind"] in ("gold", "uniform"):
            verdict = "(on the uniform curve)"
        elif speedups is None:
            verdict = "(no uniform curve to compare with)"
        else:
            verdict = ", ".join(f"{speedup_text(speedups.get(m))} {m.upper()}" for m in ("flip", "mse"))
            faster = [m.upper() for m in ("flip", "mse") if (speedups.get(m) or {}).get("faster")]
            verdict += f": faster on {' and '.join(faster)}" if faster else ": not faster"
        lines.append(f"  {run.get('label', run_name)[:30]:<30} {run['time_s']:>6.1f} s "
                     f"{run['stats'].get('mean_spp', 0):>6.1f} {flip:>7} {mse:>9}   {verdict}")
    return lines


def run(args) -> int:
    from ...addon.scene.blend_session import check_blend_file
    from ...addon.validation.runner import SceneJob
    from ...core.validation.example_scenes import resolve_scenes
    from ...core.validation.plan import parse_list
    from ...core.validation.store import check_output_folder

    settings = settings_from_args(args)
    minbound = parse_list(args.minbound_scenes, ())
    jobs = [SceneJob(name, check_blend_file(path), compare_minbound=name in minbound)
            for name, path in resolve_scenes(args.scenes)]
    out = check_output_folder(args.out)
    run_and_report(jobs, settings, out, NAME, args.quiet)
    return 0
