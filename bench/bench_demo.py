"""Benchmark: wall time of ``xsl-render demo`` from nothing (target: under 5 minutes on two
CPU cores at the default settings).

Each run starts the installed command in a fresh output folder, as a user would (so nothing
is reused but the shipped converged reference), and the median of the runs is printed with
each run's mean FLIP against the reference and its equal-quality speedup over uniform.

    .venv/bin/python bench/bench_demo.py --runs 3
    .venv/bin/python bench/bench_demo.py --runs 1 --full
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=3, help="runs; the median is printed (default 3)")
    parser.add_argument("--full", action="store_true", help="time `demo --full` instead")
    args = parser.parse_args(argv)
    exe = Path(sys.executable).with_name("xsl-render")
    times = []
    for run in range(args.runs):
        with tempfile.TemporaryDirectory(prefix="xsl-bench-demo-") as folder:
            command = [str(exe), "demo", "--out", folder, "--quiet"] + (["--full"] if args.full else [])
            started = time.perf_counter()
            result = subprocess.run(command, capture_output=True, text=True)
            seconds = time.perf_counter() - started
            if result.returncode != 0:
                print(result.stderr, file=sys.stderr)
                return result.returncode
            times.append(seconds)
            data = json.loads((Path(folder) / "results.json").read_text())
            print(f"run {run + 1}: {seconds:.1f} s")
            for name, scene in data["scenes"].items():
                for variant, entry in scene["runs"].items():
                    flip = entry["reference_metrics"]["flip"].get("mean_flip")
                    equal = (entry.get("equal_quality") or {}).get("flip") or {}
                    if entry["kind"] in ("gold", "uniform"):
                        speedup = "on the uniform curve"
                    elif equal.get("value") is None:
                        speedup = f"no equal-quality speedup ({equal.get('reason', 'no uniform curve')})"
                    else:
                        speedup = f"equal-quality speedup {equal['value']:.2f}x" + (
                            " (extrapolated)" if equal["extrapolated"] else "")
                    print(f"  {name} {variant:<20} {entry['time_s']:6.1f} s  mean FLIP {flip:.4f}  {speedup}")
    print(f"demo{' --full' if args.full else ''}: median {statistics.median(times):.1f} s over "
          f"{len(times)} run(s) (target < 300 s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
