"""Benchmark: the randomized X-map oracle suite, seed by seed, and its worst seed.

Per seed, the scene ``tests/support/random_scenes.py`` draws (64x36), X against the Cycles
oracle as ``tests/test_xmap_random.py`` judges it: mean absolute error and 99th percentile
over non-silhouette pixels with a surface, the pixels at ties (and how many were worked out,
``addon.maps.ties``), the seconds, and what the scene holds; then the worst seed by each
figure and how many pass.

    .venv/bin/python bench/bench_xmap_oracle.py                 # seeds 0-49
    .venv/bin/python bench/bench_xmap_oracle.py --seeds 0-9 --json out.json"""
from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))          # the generator and the comparison live with the tests

MAE_MAX, P99_MAX = 0.01, 0.05


def seed_list(text: str) -> list[int]:
    seeds = []
    for part in text.split(","):
        first, _, last = part.partition("-")
        seeds += range(int(first), int(last or first) + 1)
    return seeds


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="0-49", help="e.g. 0-49 or 3,7,10-12 (default 0-49)")
    parser.add_argument("--json", metavar="FILE", help="also write the per-seed figures as JSON")
    args = parser.parse_args(argv)
    import bpy
    from support.random_scenes import build_random_scene
    from support.xmap_scenes import OracleComparison

    rows = []
    print(f"{'seed':>4} {'MAE':>7} {'p99':>7} {'pixels':>6} {'ties':>5} {'model':>5} {'X s':>6} "
          f"{'all s':>6}  scene")
    for seed in seed_list(args.seeds):
        start = time.perf_counter()
        built = build_random_scene(bpy, seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            compared = OracleComparison(bpy, built.scene)
        row = {"seed": seed, "mae": compared.mae, "p99": compared.p99, "pixels": compared.pixels,
               "ties": int(compared.ties.sum()),
               "worked_out": int((compared.result.info["ties"] or {}).get("worked_out", 0)),
               "x_seconds": compared.result.info["seconds"]["total"],
               "seconds": time.perf_counter() - start, "features": built.features,
               "passes": compared.mae <= MAE_MAX and compared.p99 <= P99_MAX}
        rows.append(row)
        print(f"{seed:>4} {row['mae']:>7.4f} {row['p99']:>7.4f} {row['pixels']:>6} {row['ties']:>5} "
              f"{row['worked_out']:>5} {row['x_seconds']:>6.2f} {row['seconds']:>6.1f}  "
              f"{', '.join(built.features)}"
              + ("" if row["passes"] else "   FAILS"), flush=True)
    worst_mae = max(rows, key=lambda r: r["mae"])
    worst_p99 = max(rows, key=lambda r: r["p99"])
    passed = sum(r["passes"] for r in rows)
    print(f"\n{passed} of {len(rows)} seeds pass (MAE <= {MAE_MAX}, p99 <= {P99_MAX}); "
          f"{sum(r['ties'] > 0 for r in rows)} had ties ({sum(r['worked_out'] > 0 for r in rows)} "
          f"of them some worked out, not measured); "
          f"{sum(r['seconds'] for r in rows):.0f} s in all")
    for label, row in (("worst MAE", worst_mae), ("worst p99", worst_p99)):
        print(f"{label}: seed {row['seed']}: MAE {row['mae']:.4f}, p99 {row['p99']:.4f} over "
              f"{row['pixels']} pixels ({row['ties']} at ties); {', '.join(row['features'])}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0 if passed == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
