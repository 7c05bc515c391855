"""Benchmark: auto's own step per medium against one scene rate for all, on statue in fog.

No example scene has two heterogeneous media, so this builds one: ``statue``'s OpenVDB smoke
inside ``balls_b``'s noise fog. The fog needs a fine scene rate, which one rate for all also
gives the smoke (voxel-sized steps); auto gives the smoke the coarsest rate its bias allows
(its material's ``volume_step_rate``). Curves in this process against a converged reference:
the file's uniform, auto, auto with one rate (per-medium steps switched off) and guided at
uniform 16 and 32 spp's times; prints each point's chosen steps and its speedups over the
file and over one rate. Run on an otherwise idle machine.

    .venv/bin/python bench/bench_medium_steps.py --out bench-medium-steps --repeats 3"""
from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZE = (192, 256)
#: The fog's peak density per metre (balls_b's is 0.6 over a 14 m room; this box is 8.5 m deep).
FOG_PEAK = 0.3
METRICS = ("flip", "flip_tile95", "flip_share", "mse")


def build_scene(path: Path) -> Path:
    """statue with a noise-fog box from just in front of the camera to the wall."""
    sys.path.insert(0, str(ROOT / "example_blends"))
    import _scene_kit as kit
    import balls_b
    import statue

    statue.build()
    balls_b.PEAK_DENSITY = FOG_PEAK
    kit.mesh_object("Fog", lambda bm: kit.box(bm, (11.0, 8.5, 5.0), (0.0, 0.0, 0.0)),
                    balls_b.noise_fog_material(), location=(0.0, -1.3, 2.5))
    return kit.save(path)


def _register() -> None:
    from xsl_render.core.validation.contestants import (Contestant, CurveSpec, register_curve,
                                                        time_matched_curve, uniform_budgets)

    register_curve(time_matched_curve("guided", "guided, auto", (1 / 4, 1 / 2), curve="guided_auto",
                                      params={"importance": "none", "estimator": "auto"}))

    for name, label in (("auto", "auto, a step per medium"), ("auto_one_rate", "auto, one rate")):
        def points(ceiling: int, name=name, label=label):
            return [Contestant(f"{name}_{spp}spp", name, "uniform", f"{label} {spp} spp",
                               {"spp": spp, "estimator": "auto"}) for spp in uniform_budgets(ceiling)]
        register_curve(CurveSpec(name, label, points))


def _points(data: dict, curve: str) -> list:
    return [(name, run["seconds"], run) for name, run in data["runs"].items() if run["curve"] == curve]


def report(data: dict, one_rate: dict) -> list[str]:
    from bench_estimator import SPEEDUP_NOTE, error_cells, speedup_cell
    from xsl_render.core.validation.curves import speedups_against

    baselines = {"uniform": _points(data, "uniform"), "one_rate": _points(one_rate, "auto_one_rate")}
    lines = [f"statue in fog ({data['scene']['size'][0]}x{data['scene']['size'][1]}, "
             f"{len(data['seeds'])} repeat(s), reference {data['reference']['inputs']['spp']} spp)",
             f"{'run':30s} {'s':>6s} {'FLIP':>7s} {'p95tile':>7s} {'>0.103%':>7s} {'MSE':>9s}  chosen"
             "  | vs uniform: FLIP p95tile share MSE | vs one rate: FLIP p95tile share MSE"]
    for source in (data, one_rate):
        for name, seconds, run in _points(source, "uniform") + _points(source, "auto") \
                + _points(source, "guided_auto") + _points(source, "auto_one_rate"):
            if source is one_rate and run["curve"] == "uniform":
                continue
            stats = (run["repeats"][0].get("stats") or {}) if run["repeats"] else {}
            chosen = stats.get("estimator") or {}
            steps = "scene" if chosen.get("biased") is None else (
                "null sc." if not chosen["biased"] else f"march {chosen.get('step_rate')}"
                + "".join(f", {k.split(':', 1)[1]} {v:g}" for k, v in (chosen.get("medium_rates") or {}).items()))
            over = speedups_against(baselines, (name, seconds, run), METRICS, own_curve=None)

            def fmt(baseline, metric):
                return speedup_cell(over.get(baseline) or {}, metric)
            own = {"uniform": "uniform", "auto_one_rate": "one_rate"}.get(run["curve"])
            lines.append(error_cells(run, seconds, 30) + f"  {steps:22s} | "
                         + " ".join("   -  " if own == "uniform" else fmt("uniform", m) for m in METRICS) + " | "
                         + " ".join("   -  " if own == "one_rate" else fmt("one_rate", m) for m in METRICS))
    lines.append(SPEEDUP_NOTE)
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("bench-medium-steps"), help="folder of the curves")
    parser.add_argument("--repeats", type=int, default=3, help="repeats per run; medians (default 3)")
    args = parser.parse_args(argv)

    from xsl_render.addon.maps import estimator_choice
    from xsl_render.addon.validation.curves_runner import CurvesSettings, run_curves

    # Built once: a .blend is not byte-identical from one build to the next, and the runs
    # (and the reference) are reused only for the same file.
    blend = args.out / "statue_fog.blend"
    if not blend.exists():
        build_scene(blend)
    _register()
    settings = CurvesSettings(ceiling=64, resolution=SIZE, repeats=args.repeats,
                              curves=("uniform", "auto", "guided_auto"))
    data = run_curves(blend, settings, args.out / "media")
    # The same uniform runs for the second pass (reused, not rendered again).
    shutil.copytree(args.out / "media" / "runs", args.out / "one_rate" / "runs", dirs_exist_ok=True,
                    ignore=lambda folder, names: [n for n in names if not n.startswith("uniform_")])
    estimator_choice.step_carriers = lambda media: {}           # one scene rate for every medium
    one_rate = run_curves(blend, CurvesSettings(ceiling=64, resolution=SIZE, repeats=args.repeats,
                                                curves=("uniform", "auto_one_rate")), args.out / "one_rate")
    lines = report(data, one_rate)
    print("\n".join(lines), flush=True)
    (args.out / "bench_medium_steps.txt").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
