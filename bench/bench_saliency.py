"""Benchmark: the Itti-Koch-Niebur S map of a 512x288 image (scikit-image's "astronaut" resized):
the wall time of ``core.maps.saliency.saliency_map`` after one warm-up run.

    .venv/bin/python bench/bench_saliency.py [--runs N]"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from skimage import data, transform

from xsl_render.core.maps.saliency import saliency_map
from xsl_render.core.maps.saliency_input import modulated_saliency_map

WIDTH, HEIGHT = 512, 288
TARGET_S = 0.3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=9, help="timed runs (at least 5)")
    runs = max(5, parser.parse_args().runs)

    image = transform.resize(data.astronaut(), (HEIGHT, WIDTH), anti_aliasing=True)
    image = image.astype(np.float32)
    rng = np.random.default_rng(0)
    snapshot_hdr = (image ** 2.2) * 8.0                       # a scene-linear stand-in
    x_map = np.clip(rng.random((HEIGHT, WIDTH), dtype=np.float32), 0.05, 1.0)

    for label, job in (("S of a display image", lambda: saliency_map(image)),
                       ("S map from HDR snapshot + X (tone map included)",
                        lambda: modulated_saliency_map(snapshot_hdr, x_map))):
        job()                                                  # warm-up (kernel spectra)
        times = []
        for _ in range(runs):
            started = time.perf_counter()
            job()
            times.append(time.perf_counter() - started)
        median = statistics.median(times)
        verdict = "ok" if median <= TARGET_S else "TOO SLOW"
        print(f"{label}, {WIDTH}x{HEIGHT}: median {median:.3f} s over {runs} runs "
              f"(min {min(times):.3f}, max {max(times):.3f}); target <= {TARGET_S} s: {verdict}")


if __name__ == "__main__":
    main()
