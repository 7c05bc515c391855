"""Benchmark: each step rate auto may choose, against the file, beside auto's predicted error.

The calibration of auto's tolerance (``core.sampling.volume_estimator``). For each seed of the
lit-scene suite (``tests/support/lit_scenes.py``, the scenes and converged references of
``bench/bench_auto_lit.py`` reused from ``--cache``): ray marching at each candidate rate
with the file's other settings (``--estimator biased --step-rate R``) at 16 spp, and at 64
spp the rates not visibly worse at 16 (a bias stands while the noise falls), its
quality at equal samples over the file's (mean FLIP, p95-tile FLIP, MSE), and auto's
predicted picture error at that rate (``core.media.light_paths``). A rate is *visibly worse*
as auto would be (``support.lit_judge``): p95-tile FLIP above 1.1x or MSE above 1.25x the
file's. The report gives, per rate and count, the predicted error and the verdict, and the
largest tolerance constant (``NOISE_AT_ONE_SPP``) that lets no visibly worse rate through.
Equal samples only: nothing is timed, so it may run beside other work.

    .venv/bin/python bench/bench_auto_rates.py --seeds 0-59 --cache ~/lit-cache
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from bench_xmap_oracle import seed_list  # noqa: E402

RATES = (4.0, 2.0, 1.0, 0.5, 0.25)
SPP = (16, 64)


def register(spp: int, rates) -> tuple[str, str]:
    from xsl_render.core.validation.contestants import Contestant, CurveSpec, register_curve

    def file_points(ceiling: int):
        return [Contestant(f"file_{spp}spp", "file", "uniform", f"file {spp} spp", {"spp": spp})]

    def rate_points(ceiling: int):
        return [Contestant(f"rate{rate:g}_{spp}spp", "rates", "uniform", f"rate {rate:g} {spp} spp",
                           {"spp": spp, "estimator": "biased", "step_rate": rate}) for rate in rates]

    register_curve(CurveSpec("file", "the file's own settings", file_points, baseline=True))
    register_curve(CurveSpec("rates", "ray marching at each rate", rate_points))
    return ("file", "rates")


def predicted(bpy, blend: Path) -> dict:
    """Auto's predicted picture error at every candidate rate (a count so high that no rate
    passes makes it try them all), and its reason."""
    from xsl_render.addon.maps.estimator_choice import choose_estimator
    from xsl_render.core.sampling.render_options import RenderOptions

    bpy.ops.wm.open_mainfile(filepath=str(blend))
    choice = choose_estimator(bpy.context.scene, RenderOptions(max_spp=1 << 20, estimator="auto"), 1 << 20)
    return {"tried": {f"{rate:g}": value for rate, value in (choice.tried or {}).items()},
            "reason": choice.reason, "biased": choice.biased}


def run_seed(bpy, seed: int, cache: Path, out: Path, size) -> dict | None:
    from support.lit_judge import MSE_WORSE, VISIBLY_WORSE
    from support.lit_scenes import saved_lit_scene
    from xsl_render.addon.validation.curves_runner import CurvesJob, CurvesSettings
    from xsl_render.core.validation.contestants import CURVES

    blend, built = saved_lit_scene(bpy, seed, cache / "lit_scenes", *size)
    prediction = predicted(bpy, blend)
    rows, rates = {}, RATES
    for spp in SPP:
        # A rate visibly worse at fewer samples is worse at more (its bias stands still while
        # the noise falls): only the others are rendered again.
        registered = list(CURVES)
        try:
            settings = CurvesSettings(ceiling=max(SPP), resolution=tuple(size), repeats=1,
                                      curves=register(spp, rates), vdp=False, reference_spp=1024)
            runs = CurvesJob(blend, settings, out / f"seed_{seed:03d}").run()["runs"]
        finally:
            CURVES[:] = registered
        file = runs[f"file_{spp}spp"]
        for rate in rates:
            run = runs[f"rate{rate:g}_{spp}spp"]
            ratio = {m: run[m] / file[m] if file.get(m) else None for m in ("flip", "flip_tile95", "mse")}
            worse = ratio["flip_tile95"] > VISIBLY_WORSE or ratio["mse"] > MSE_WORSE
            rows[f"{rate:g}@{spp}"] = {"ratio": ratio, "worse": bool(worse)}
        rates = tuple(r for r in rates if not rows[f"{r:g}@{spp}"]["worse"])
        if not rates:
            break
    return {"seed": seed, "kind": built.kind, "scene": built.describe(), "predicted": prediction, "rows": rows}


def tolerance_constant(results) -> tuple[float, list]:
    """The largest constant C (tolerance C / sqrt(spp)) under which no visibly worse rate's
    predicted error passes, and the accepted good rates at it."""
    worst = math.inf
    for result in results:
        for key, row in result["rows"].items():
            rate, spp = key.split("@")
            value = result["predicted"]["tried"].get(rate)
            if row["worse"] and value is not None:
                worst = min(worst, value * math.sqrt(int(spp)))
    accepted = [(r["seed"], key) for r in results for key, row in r["rows"].items()
                if not row["worse"] and (v := r["predicted"]["tried"].get(key.split("@")[0])) is not None
                and v * math.sqrt(int(key.split("@")[1])) < worst]
    return worst, accepted


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="0-59")
    parser.add_argument("--cache", type=Path, required=True, help="bench_auto_lit's --cache (scenes, references)")
    parser.add_argument("--out", type=Path, default=None, help="folder of the runs (default CACHE/bench-auto-rates)")
    parser.add_argument("--size", default="320x180")
    parser.add_argument("--report", type=Path, default=ROOT / "docs" / "bench_auto_rates.txt")
    args = parser.parse_args(argv)
    try:
        seeds = seed_list(args.seeds)
        size = tuple(int(v) for v in args.size.lower().split("x"))
    except ValueError:
        parser.exit(2, "bench_auto_rates: --seeds or --size is not a list of numbers\n")
    import os

    os.environ["XSL_RENDER_CACHE"] = str(args.cache / "references")
    import bpy

    out = args.out or args.cache / "bench-auto-rates"
    results = []
    for seed in seeds:
        result = run_seed(bpy, seed, args.cache, out, size)
        results.append(result)
        (out / "results.json").write_text(json.dumps(results, indent=1))
        line = "  ".join(f"{key}:{row['ratio']['flip_tile95']:.2f}{'!' if row['worse'] else ''}"
                         f"({result['predicted']['tried'].get(key.split('@')[0], float('nan')):.3f})"
                         for key, row in result["rows"].items())
        print(f"seed {seed:3d} {result['kind']:16s} {line}", flush=True)
    constant, accepted = tolerance_constant(results)
    lines = [f"# {__doc__.splitlines()[0]}", "",
             "seed kind: per rate@spp, p95-tile FLIP over the file's (! visibly worse) and (predicted error)", ""]
    for result in results:
        lines.append(f"seed {result['seed']:3d} {result['kind']:16s} " + "  ".join(
            f"{key}:{row['ratio']['flip_tile95']:.2f}/{row['ratio']['mse']:.2f}{'!' if row['worse'] else ''}"
            f"({result['predicted']['tried'].get(key.split('@')[0], float('nan')):.3f})"
            for key, row in result["rows"].items()))
    lines += ["", f"largest tolerance constant letting no visibly worse rate through: {constant:.4f}",
              f"good rates it accepts: {len(accepted)} of "
              f"{sum(not row['worse'] for r in results for row in r['rows'].values())}"]
    args.report.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[-2:]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
