"""Benchmark: an animation rendered in one Cycles session, and what ``guided`` gets over it.

On ``street`` (24 frames, a camera dollying through static noise fog), each run a whole
``xsl-render`` process: 1. one process for the frames against one per frame (wall time, and
Cycles' sync per frame); 2. quality along the sequence against each frame's converged
reference: the file's uniform curve (8..64 spp), auto at 16 spp, guided at uniform 16 and 32
spp's per-frame time, xsl; means over frames of each criterion, flicker, video JOD, and the
equal-quality speedups; 3. guided's process time over its frames' render-only times
(``--overhead``). Run it on an otherwise idle machine.

    .venv/bin/python bench/bench_animation.py --out bench-animation --repeats 3
    .venv/bin/python bench/bench_animation.py --overhead --skip-sessions --skip-quality"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENE = "street"
UNIFORM_SPP = (8, 16, 32, 64)
EQUAL_TIME_SPP = (16, 32)
METRICS = ("flip", "flip_tile95", "flip_share", "mse")
MAX_SPP = 64


def xsl(*args) -> tuple[float, subprocess.CompletedProcess]:
    """Run ``xsl-render ARGS`` as its own process; (wall seconds, the process)."""
    started = time.perf_counter()
    done = subprocess.run([str(ROOT / ".venv" / "bin" / "xsl-render"), *map(str, args)],
                          capture_output=True, text=True)
    seconds = time.perf_counter() - started
    if done.returncode != 0:
        sys.exit(f"xsl-render {' '.join(map(str, args))} failed:\n{done.stderr[-2000:]}")
    return seconds, done


def render_only_seconds(frames: list[dict]) -> float:
    """The frames' wall time less what Cycles reported syncing."""
    return sum(stats["wall_s"] - stats.get("cycles_sync_s", 0.0) for stats in frames)


def scene_path() -> Path:
    return ROOT / "example_blends" / f"{SCENE}.blend"


def render_frames(folder: Path, frames: str, *args, scene: Path | None = None) -> dict:
    """One process rendering ``frames`` of ``scene`` (the example): its wall time and per-frame stats."""
    folder.mkdir(parents=True, exist_ok=True)
    seconds, _ = xsl("render", scene or scene_path(), "--frames", frames, "--max-spp", MAX_SPP, "--quiet",
                     "--out", folder / "frame_####.exr", "--stats", folder / "stats.json", *args)
    stats = json.loads((folder / "stats.json").read_text())
    return {"seconds": seconds, "frames": stats["frames"]}


def measure(reference: Path, folder: Path, frames: str, video: bool) -> dict:
    """``xsl-render compare`` of the run's frames against the references (with ``video``,
    ColorVideoVDP's JOD of the sequence played at 24 fps too; per-frame VDP is not asked)."""
    _, _ = xsl("compare", reference / "frame_####.exr", folder / "frame_####.exr", "--frames", frames,
               *(() if video else ("--no-vdp",)), "--json", folder / "compare.json")
    summary = json.loads((folder / "compare.json").read_text())["sequence"]
    values = {metric: summary["mean"][metric] for metric in METRICS}
    values["flicker"] = summary["flicker"]["flicker"]
    values["jod"] = summary["vdp"].get("jod")
    return values


def median_run(repeats: int, run) -> dict:
    """The run of median wall time among ``repeats`` (its metrics go with it)."""
    runs = sorted((run(index) for index in range(repeats)), key=lambda r: r["seconds"])
    return runs[len(runs) // 2]


def sessions(out: Path, frames: str, count: int, repeats: int) -> None:
    from xsl_render.core.frames import parse_frame_list

    listed = parse_frame_list(frames)[:count]
    one = median_run(repeats, lambda i: render_frames(out / "sessions" / f"one_{i}", frames,
                                                      "--mode", "uniform", "--spp", 16))
    separate = []
    for frame in listed:
        times = []
        for i in range(repeats):
            folder = out / "sessions" / f"separate_{frame}_{i}"
            folder.mkdir(parents=True, exist_ok=True)
            seconds, _ = xsl("render", scene_path(), "--frame", frame, "--max-spp", MAX_SPP, "--quiet",
                             "--mode", "uniform", "--spp", 16, "--out", folder / "f.exr",
                             "--stats", folder / "stats.json")
            stats = json.loads((folder / "stats.json").read_text())
            times.append((seconds, stats["wall_s"], stats["cycles_sync_s"]))
        separate.append(sorted(times)[len(times) // 2])
    print(f"\n## sessions: uniform 16 spp, {SCENE} (median of {repeats})")
    print("| frame | one process: frame wall s | Cycles sync s | own process: process s | frame wall s | sync s |")
    print("|---|---|---|---|---|---|")
    for index, stats in enumerate(one["frames"]):
        own = separate[index] if index < len(separate) else None
        tail = (f"{own[0]:.2f} | {own[1]:.2f} | {own[2]:.2f}" if own else "| |")
        print(f"| {stats['frame']} | {stats['wall_s']:.2f} | {stats['cycles_sync_s']:.2f} | {tail} |")
    n = len(one["frames"])
    per_frame_separate = statistics.mean(own[0] for own in separate)
    print(f"\nwhole sequence in one process: {one['seconds']:.1f} s for {n} frames "
          f"({one['seconds'] / n:.2f} s a frame); a process per frame: {per_frame_separate:.2f} s a "
          f"frame ({per_frame_separate * n:.1f} s for {n}): {per_frame_separate * n / one['seconds']:.2f}x")


def quality(out: Path, frames: str, repeats: int, blue_noise: bool = False, with_xsl: bool = True) -> None:
    from xsl_render.core.validation.curves import Point, as_error, equal_quality_speedup
    from xsl_render.core.validation.vdp import vdp_unavailable_reason

    video = vdp_unavailable_reason() is None
    criteria = METRICS + ("flicker",) + (("jod",) if video else ())

    reference = out / "reference"
    xsl("reference", scene_path(), "--frames", frames, "--max-spp", MAX_SPP, "--quiet",
        "--out", reference / "frame_####.exr")
    runs: dict[str, dict] = {}

    def run(name: str, *args, scene: Path | None = None) -> dict:
        def once(i):
            folder = out / "runs" / f"{name}_{i}"
            result = render_frames(folder, frames, *args, scene=scene)
            return result | {"folder": folder}

        chosen = median_run(repeats, once)
        chosen["metrics"] = measure(reference, chosen["folder"], frames, video)
        runs[name] = chosen
        return chosen

    for spp in UNIFORM_SPP:
        run(f"uniform_{spp}", "--mode", "uniform", "--spp", spp)
    run("auto_16", "--mode", "uniform", "--spp", 16, "--estimator", "auto")
    for spp in EQUAL_TIME_SPP:
        frames_run = runs[f"uniform_{spp}"]["frames"]
        budget = sum(stats["wall_s"] for stats in frames_run) / len(frames_run)
        guided = run(f"guided_{spp}", "--mode", "guided", "--time-budget", f"{budget:.3f}")
        guided["budget"] = budget

    if with_xsl:
        run("xsl", "--mode", "xsl")      # the paper's map, ceiling 64: its flicker
    if blue_noise:
        # What a file made in Blender 5 renders with (street, like every example, carries the
        # legacy pattern, which auto and guided replace): the baseline for such a file.
        from scene_copy import cycles_copy

        from xsl_render.core.sampling.sample_pattern import BLENDER_DEFAULT

        copy = cycles_copy(SCENE, out, sampling_pattern=BLENDER_DEFAULT)
        for spp in UNIFORM_SPP[:-1]:
            run(f"blue_noise_uniform_{spp}", "--mode", "uniform", "--spp", spp, scene=copy)

    print(f"\n## quality along the sequence: {SCENE}, frames {frames} (median of {repeats}; times "
          "are whole processes)")
    print("| run | s | mean FLIP | p95 tile FLIP | FLIP>0.103 % | MSE | flicker | video JOD |")
    print("|---|---|---|---|---|---|---|---|")
    for name, result in runs.items():
        m = result["metrics"]
        jod = "n/a" if m["jod"] is None else f"{m['jod']:.3f}"
        print(f"| {name} | {result['seconds']:.1f} | {m['flip']:.4f} | {m['flip_tile95']:.4f} | "
              f"{m['flip_share']:.2f} | {m['mse']:.3g} | {m['flicker']:.4f} | {jod} |")
    if not video:
        print(f"(video JOD not measured: {vdp_unavailable_reason()})")
    for baseline in ("uniform", "blue_noise_uniform")[:1 + blue_noise]:
        print(f"\nequal-quality speedup over {baseline.replace('_', ' ')} (scene settings), each metric:")
        for name, result in runs.items():
            if name.startswith(baseline):
                continue
            cells = []
            for metric in criteria:
                curve = [Point(r["seconds"], as_error(metric, r["metrics"][metric]), n)
                         for n, r in runs.items() if n.startswith(baseline)]
                speedup = equal_quality_speedup(curve, as_error(metric, result["metrics"][metric]),
                                                result["seconds"])
                value = ("n/a" if speedup.value is None
                         else f"{speedup.value:.2f}x" + ("*" if speedup.extrapolated else ""))
                cells.append(f"{metric} {value}")
            print(f"  {name}: " + ", ".join(cells))
    for spp in EQUAL_TIME_SPP:
        guided = runs[f"guided_{spp}"]
        render_only = render_only_seconds(guided["frames"])
        print(f"guided at uniform {spp}'s time ({guided['budget']:.2f} s a frame): process "
              f"{guided['seconds']:.1f} s against {render_only:.1f} s of its frames' render-only time "
              f"({guided['seconds'] / render_only:.3f}x); estimator steps chosen: "
              + ", ".join(sorted({str(stats['estimator'].get('step_rate')) for stats in guided['frames']}))
              + "; spp per frame: " + ", ".join(f"{stats['mean_spp']:g}" for stats in guided["frames"]))
    (out / "animation.json").write_text(json.dumps(
        {name: {k: v for k, v in r.items() if k != "folder"} for name, r in runs.items()}, indent=1,
        default=str))


def guided_overhead(out: Path, frames: str, repeats: int) -> None:
    """Guided over ``frames`` at uniform 16 spp's per-frame time: the whole process against
    the sum of its frames' render-only times (issue 21's "within 1.15x")."""
    uniform = median_run(repeats, lambda i: render_frames(out / "overhead" / f"uniform_{i}", frames,
                                                          "--mode", "uniform", "--spp", 16))
    budget = sum(stats["wall_s"] for stats in uniform["frames"]) / len(uniform["frames"])
    guided = median_run(repeats, lambda i: render_frames(out / "overhead" / f"guided_{i}", frames,
                                                         "--mode", "guided", "--time-budget", f"{budget:.3f}"))
    render_only = render_only_seconds(guided["frames"])
    frame_wall = sum(stats["wall_s"] for stats in guided["frames"])
    n = len(guided["frames"])
    print(f"\n## guided's overhead: {SCENE}, frames {frames} (median of {repeats})")
    print(f"uniform 16 spp: process {uniform['seconds']:.1f} s, {budget:.2f} s a frame (its frames' wall)")
    print(f"guided at that budget: process {guided['seconds']:.1f} s for {n} frames; frames' wall "
          f"{frame_wall:.1f} s (budget {budget * n:.1f} s); render-only {render_only:.1f} s; "
          f"process / render-only {guided['seconds'] / render_only:.3f}x; mean spp "
          + ", ".join(f"{stats['mean_spp']:g}" for stats in guided["frames"]))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("bench-animation"))
    parser.add_argument("--frames", default="1-24")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--separate-frames", type=int, default=4,
                        help="frames rendered one process each for the sessions table")
    parser.add_argument("--skip-sessions", action="store_true")
    parser.add_argument("--skip-quality", action="store_true")
    parser.add_argument("--blue-noise", action="store_true",
                        help="also uniform at 8-32 spp on a copy set to Blender 5's sample pattern")
    parser.add_argument("--skip-xsl", action="store_true")
    parser.add_argument("--overhead", action="store_true",
                        help="also guided's process time against its frames' render-only time")
    args = parser.parse_args(argv)
    if not args.skip_sessions:
        sessions(args.out, args.frames, args.separate_frames, args.repeats)
    if not args.skip_quality:
        quality(args.out, args.frames, args.repeats, args.blue_noise, not args.skip_xsl)
    if args.overhead:
        guided_overhead(args.out, args.frames, args.repeats)
    return 0


if __name__ == "__main__":
    sys.exit(main())
