"""Benchmark: ``--estimator auto`` against the file's own settings on random lit scenes.

Issue 43's suite. Each seed is a scene ``tests/support/lit_scenes.py`` draws (a kind per seed:
world fog, fog boxes and blobs, dense sun-lit clouds, emissive volumes, OpenVDB smoke, smoke
in fog, world water; 1-3 lamps and a world light), saved once as a new Blender 5 file has
it (blue noise, null scattering, OIDN). Per seed (``tests/support/lit_judge.py``):

- the file as it is (uniform sampling, its own settings) and ``--estimator auto``, at each
  count of ``--spp`` (default 16, 64), against a converged reference of another seed at
  1024 spp (``--reference-spp``); the subset of seeds divisible by ``SUBSET_EVERY`` also at
  256 spp against a reference of 4 x as many samples (4096); every run and reference
  denoised as the project denoises every run;
- at equal samples: auto's mean FLIP, p95 of 32-px tile FLIP, share of pixels above FLIP
  0.103 and MSE over the file's (ColorVideoVDP's JOD too where installed); visibly worse
  where the p95-tile FLIP is more than ``VISIBLY_WORSE`` (1.1) times the file's;
- timed (not ``--quality-only``): the file's curve (its uniform renders at 4 .. 256 spp; at
  64 .. 1024 for the subset's 256), each run timed as a whole (scene sync and octree, auto's
  prediction, denoising), and auto's equal-quality speedup over it on each figure.

Seeds whose reference is almost black (mean display value below ``DARK_DISPLAY``, 0.02) are
dropped from the figures, by that rule alone. The .blend files are kept under
``CACHE/lit_scenes``, the references in the project's reference cache (``CACHE/references``
with ``--cache CACHE``, else the user cache), each keyed by the file's bytes and the
settings; a rerun reuses both, and every finished run whose inputs (auto's: the package's
sources too) are unchanged, so a new auto renders only auto's runs. A seed's verdict is kept
in OUT/<mode>/seed_NNN.json and reused while nothing it depends on changed.

Writes the per-seed table and the distribution (min, quartiles, max) per criterion and per
kind to ``--report`` (default docs/bench_auto_lit.txt, timed; docs/bench_auto_lit_quality.txt,
--quality-only) and the raw results to OUT/<mode>/bench_auto_lit.json. Time only on an
otherwise idle machine; ``--quality-only`` measures no time and may run beside other work.

    .venv/bin/python bench/bench_auto_lit.py --quality-only --seeds 0-59 --cache ~/lit-cache
    .venv/bin/python bench/bench_auto_lit.py --seeds 0-59 --cache ~/lit-cache --repeats 3
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))          # the generator and the judge live with the tests

from bench_xmap_oracle import seed_list  # noqa: E402
from performance_doc import write_bench_output  # noqa: E402
from support.lit_judge import (DARK_DISPLAY, METRICS, VISIBLY_WORSE, Tier, choice_text,  # noqa: E402
                               is_dark, ratio_text)

#: Seeds divisible by this also render at the subset's counts against references of 4x the
#: samples.
SUBSET_EVERY = 5
#: The file's curve (timed) for the default counts, and the subset's counts and curve.
CURVE = (4, 8, 16, 32, 64, 128, 256)
SUBSET_SPP = (256,)
SUBSET_CURVE = (64, 128, 256, 512, 1024)
SUBSET_REFERENCE_FACTOR = 4
QUANTILES = (0, 25, 50, 75, 100)
#: The issue's bars: every seed's speedup at least this, the median on mean FLIP at least MEDIAN_BAR.
SPEEDUP_BAR, MEDIAN_BAR = 0.95, 1.5
LABELS = {"flip": "mean FLIP", "flip_tile95": "p95-tile FLIP", "flip_share": "share > 0.103", "mse": "MSE"}


def parse(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    parser.add_argument("--seeds", default="0-59", help="e.g. 0-59 or 3,7,10-12 (default 0-59)")
    parser.add_argument("--spp", default="16,64", help="counts auto and the file are compared at (default 16,64)")
    parser.add_argument("--size", default="320x180", help="frame size WxH (default 320x180)")
    parser.add_argument("--reference-spp", type=int, default=1024,
                        help=f"the references' samples (default 1024; the subset's: {SUBSET_REFERENCE_FACTOR}x)")
    parser.add_argument("--no-subset", action="store_true", help=f"leave out the subset's {SUBSET_SPP[0]} spp")
    parser.add_argument("--quality-only", action="store_true",
                        help="equal samples only: no time curves, nothing timed (safe on a busy machine)")
    parser.add_argument("--repeats", type=int, default=1, help="repeats per timed run; medians (default 1)")
    parser.add_argument("--out", type=Path, default=Path("bench-auto-lit"), help="folder of the runs")
    parser.add_argument("--cache", type=Path, default=None,
                        help="folder of the scenes and references (default: the project's user cache)")
    parser.add_argument("--report", type=Path, default=None, help="the text report (default: docs/bench_auto_lit*.txt)")
    args = parser.parse_args(argv)
    try:
        args.seeds = seed_list(args.seeds)
        args.spp = tuple(sorted({int(v) for v in args.spp.split(",")}))
        args.size = tuple(int(v) for v in args.size.lower().split("x"))
    except ValueError:
        parser.exit(2, "bench_auto_lit: --seeds, --spp or --size is not a list of numbers\n")
    if len(args.size) != 2 or min(args.size) < 8 or min(args.spp) < 1 or args.reference_spp < 1 or args.repeats < 1:
        parser.exit(2, "bench_auto_lit: --size must be WxH (8 or more each), --spp, --reference-spp "
                       "and --repeats at least 1\n")
    if args.report is None:
        args.report = ROOT / "docs" / ("bench_auto_lit_quality.txt" if args.quality_only else "bench_auto_lit.txt")
    return args


def tiers_of(seed: int, args) -> list[Tier]:
    tiers = [Tier(args.reference_spp, args.spp, CURVE)]
    if not args.no_subset and seed % SUBSET_EVERY == 0:
        tiers.append(Tier(SUBSET_REFERENCE_FACTOR * args.reference_spp, SUBSET_SPP, SUBSET_CURVE))
    return tiers


def judge_seed(bpy, seed: int, args, scenes: Path, folder: Path) -> dict:
    """A seed's verdict, reused from ``folder/seed_NNN.json`` while its inputs are the same."""
    import json

    from support.lit_judge import auto_source_hash, run_tier, verdict
    from support.lit_scenes import GENERATOR_VERSION, saved_lit_scene
    from xsl_render.core.files import write_json
    from xsl_render.core.validation.store import inputs_hash

    timed = not args.quality_only
    tiers = tiers_of(seed, args)
    inputs = {"seed": seed, "size": list(args.size), "generator": GENERATOR_VERSION, "timed": timed,
              "repeats": args.repeats if timed else 1, "auto_source": auto_source_hash(),
              "tiers": [[t.reference_spp, list(t.spp), list(t.curve)] for t in tiers]}
    key = inputs_hash(inputs)
    path = folder / f"seed_{seed:03d}.json"
    if path.is_file():
        kept = json.loads(path.read_text())
        if kept.get("key") == key:
            return {**kept, "reused": True}
    started = time.perf_counter()
    blend, built = saved_lit_scene(bpy, seed, scenes, *args.size)
    result = {"key": key, "inputs": inputs, "seed": seed, "kind": built.kind, "scene": built.describe(),
              "blend": str(blend), "tiers": {}}
    for tier in tiers:
        data = run_tier(blend, tier, args.size, folder / f"seed_{seed:03d}" / f"ref{tier.reference_spp}",
                        timed=timed, repeats=args.repeats if timed else 1)
        result["tiers"][str(tier.reference_spp)] = verdict(data, tier)
    result["seconds"] = time.perf_counter() - started
    write_json(path, result)
    return {**result, "reused": False}


# --- the report ---------------------------------------------------------------------------

def _counts(results):
    """Every (reference spp, count) present, in order."""
    return sorted({(int(ref), int(spp)) for r in results for ref, tier in r["tiers"].items()
                   for spp in tier["counts"]}, key=lambda pair: (pair[0], pair[1]))


def _quantiles(values) -> str:
    values = [v for v in values if v is not None and np.isfinite(v)]
    if not values:
        return "   -"
    q = np.percentile(values, QUANTILES)
    return f"{len(values):3d}  " + " ".join(f"{v:7.3f}" for v in q)


def seed_line(result: dict, counts, timed: bool) -> str:
    cells = [f"{result['seed']:4d} {result['kind'][:15]:15s}"]
    for ref, spp in counts:
        entry = result["tiers"].get(str(ref), {}).get("counts", {}).get(str(spp))
        if entry is None:
            cells.append(" " * (43 + (18 if timed else 0)))
            continue
        ratio = entry["ratio"]
        cell = (f"{choice_text(entry['choice'])[:10]:>10s} {entry['file']['flip_tile95']:6.3f} "
                f"{entry['auto']['flip_tile95']:6.3f} {ratio_text(ratio['flip_tile95'])} "
                f"{ratio_text(ratio['mse'])} {ratio_text(ratio['flip'])} {'WORSE' if entry['visibly_worse'] else '     '}")
        if timed:
            cell += " " + " ".join(ratio_text(entry["speedup"][m]) for m in ("flip", "flip_tile95", "mse"))
        cells.append(cell)
    reference = result["tiers"][min(result["tiers"], key=int)]["reference"]
    return " | ".join(cells) + f" | {reference['display_mean']:5.3f} {reference.get('render_s') or 0:6.0f}"


def report(results: list[dict], args) -> list[str]:
    timed = not args.quality_only
    counts = _counts(results)
    kept = [r for r in results if not is_dark(next(iter(r["tiers"].values())))]
    dropped = [r for r in results if r not in kept]
    lines = [f"bench_auto_lit: {len(results)} seeds ({args.size[0]}x{args.size[1]}), "
             + ("timed, " + f"median of {args.repeats}" if timed else "equal samples only (--quality-only), nothing timed")
             + f"; auto at {', '.join(f'{spp} spp (reference {ref})' for ref, spp in counts)}",
             f"subset: seeds divisible by {SUBSET_EVERY}; dropped (reference's mean display value below "
             f"{DARK_DISPLAY}): {', '.join(str(r['seed']) for r in dropped) or 'none'}",
             f"visibly worse: auto's p95-tile FLIP above {VISIBLY_WORSE} x the file's at equal samples", ""]
    head = "seed kind           "
    for ref, spp in counts:
        head += f" | {spp:>4d} spp: choice  p95 f  p95 a  p95x  MSEx FLIPx      " + (" suFL su95 suMSE" if timed else "")
    lines += [head + " | ref-disp ref-s", *(seed_line(r, counts, timed) for r in results)]
    lines += ["", "x = auto over the file at equal samples; su = equal-quality speedup over the file's curve; "
              "ref-disp = the reference's mean display value, ref-s = its render seconds (1st tier)"]
    for ref, spp in counts:
        entries = [(r, r["tiers"][str(ref)]["counts"][str(spp)]) for r in kept
                   if str(spp) in r["tiers"].get(str(ref), {}).get("counts", {})]
        if not entries:
            continue
        worse = [(r, e) for r, e in entries if e["visibly_worse"]]
        lines += ["", f"{spp} spp against {ref}-spp references: {len(entries)} seeds, visibly worse "
                      f"{len(worse)}: " + ", ".join(f"{r['seed']} ({r['kind']}, p95 x{e['ratio']['flip_tile95']:.2f})"
                                                    for r, e in worse),
                  f"  {'criterion':34s}   n      min      q1  median      q3     max"]
        for m in METRICS:
            lines.append(f"  auto/file {LABELS[m]:24s} {_quantiles(e['ratio'][m] for _, e in entries)}")
        if timed:
            for m in METRICS:
                values = [e["speedup"][m] for _, e in entries]
                below = sum(1 for v in values if v is not None and v < SPEEDUP_BAR)
                lines.append(f"  speedup on {LABELS[m]:23s} {_quantiles(values)}   below {SPEEDUP_BAR}: {below}")
        kinds = sorted({r["kind"] for r, _ in entries})
        lines.append("  per kind:")
        for kind in kinds:
            mine = [e for r, e in entries if r["kind"] == kind]
            lines.append(f"    {kind + ', p95-tile auto/file':32s} {_quantiles(e['ratio']['flip_tile95'] for e in mine)}")
            lines.append(f"    {kind + ', MSE auto/file':32s} {_quantiles(e['ratio']['mse'] for e in mine)}")
            if timed:
                lines.append(f"    {kind + ', speedup mean FLIP':32s} {_quantiles(e['speedup']['flip'] for e in mine)}")
    if timed:
        lines.append(f"\nbars (issue 43): every speedup >= {SPEEDUP_BAR} on mean FLIP, p95-tile FLIP and MSE; "
                     f"median on mean FLIP >= {MEDIAN_BAR} at {', '.join(str(s) for _, s in counts if s in args.spp)} spp")
    lines += ["", "the worst seeds (p95-tile FLIP auto/file, the largest over their counts):"]
    worst = sorted(kept, key=lambda r: -max(e["ratio"]["flip_tile95"] or 0 for t in r["tiers"].values()
                                            for e in t["counts"].values()))[:8]
    for r in worst:
        ratios = ", ".join(f"{spp} spp x{e['ratio']['flip_tile95']:.2f} (MSE x{e['ratio']['mse']:.2f}, "
                           f"{choice_text(e['choice'])})" for t in r["tiers"].values() for spp, e in t["counts"].items())
        lines.append(f"  {r['scene']}\n    {ratios}")
    return lines


def main(argv=None) -> int:
    args = parse(argv)
    if args.cache is not None:
        args.cache = args.cache.expanduser().resolve()
        os.environ["XSL_RENDER_CACHE"] = str(args.cache)
    import bpy

    from xsl_render.core.files import write_json, write_text
    from xsl_render.core.validation.reference import cache_root

    scenes = cache_root() / "lit_scenes"
    folder = args.out.resolve() / ("quality" if args.quality_only else "timed")
    results = []
    for seed in args.seeds:
        result = judge_seed(bpy, seed, args, scenes, folder)
        results.append(result)
        spent = "reused" if result["reused"] else f"{result['seconds']:.0f} s"
        print(seed_line(result, _counts([result]), not args.quality_only) + f" | {spent}  {result['scene']}",
              flush=True)
    write_json(folder / "bench_auto_lit.json", {"settings": {k: (str(v) if isinstance(v, Path) else v)
                                                             for k, v in vars(args).items()},
                                                "results": results})
    lines = report(results, args)
    write_text(args.report, "\n".join(lines) + "\n")
    print("\n".join(lines))
    if args.report.resolve().parent == ROOT / "docs":
        # performance.md gets the distributions; the per-seed table stays in the report.
        table_end = lines.index("", 4)
        summary = lines[:3] + [f"(per seed: docs/{args.report.name})"] + lines[table_end + 2:]
        write_bench_output("auto_lit", "Random lit scenes (bench_auto_lit.py)", "bench_auto_lit.py", argv,
                           summary)
    return 0


if __name__ == "__main__":
    sys.exit(main())
