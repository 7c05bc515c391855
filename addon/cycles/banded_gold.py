"""The gold standard rendered in horizontal bands, so that the panel can stop it with ESC.

``selective_render.render_gold`` is one ordinary Cycles render: nothing can run between its
first and last sample, so a modal operator could neither redraw the interface nor cancel.
Here the frame is cut into full-width bands, each rendered with ``max_spp`` and
``EXACT_MARGIN`` extra rows above and below (cropped away). With that margin every pixel is
bit-identical to the same pixel of one full-frame render with the same seed (the guarantee
``tests/test_selective_render.py`` checks for tiles, and ``tests/test_panel_operators.py``
for these bands), so the image *is* the gold standard; only its wall time carries the
margin's extra rows. The command line and background scripts use ``render_gold``.
"""
from __future__ import annotations

import math
import time

from ...core.progress import Steps
from ...core.sampling.composite import Compositor, crop, render_window
from ...core.sampling.render_options import EXACT_MARGIN, RenderOptions
from ..scene.state import preserved_scene
from .selective_render import (RenderOutcome, finish_image, guide_prefilter, prepare_render, render_stats,
                               tile_entry)
from .tile_render import CyclesWindowRenderer

#: Pixel-samples per band: a few seconds of fog on two CPU cores, so ESC answers quickly.
BAND_PIXEL_SAMPLES = 2_000_000


def band_rows(width: int, height: int, spp: int, budget: int = BAND_PIXEL_SAMPLES) -> int:
    """Rows per band: about ``budget`` pixel-samples, never fewer rows than the two margins
    (thinner bands would spend most of their samples on rows that are cropped away)."""
    rows = math.ceil(budget / max(1, width * spp))
    return int(min(height, max(2 * EXACT_MARGIN, rows)))


def gold_band_steps(scene, options: RenderOptions, budget: int = BAND_PIXEL_SAMPLES) -> Steps[RenderOutcome]:
    """The gold standard (``max_spp`` everywhere) as steps, one band per step."""
    with preserved_scene(scene):
        width, height, warnings = prepare_render(scene, options)
        rows = band_rows(width, height, options.max_spp, budget)
        bands = [(row, min(height, row + rows), 0, width) for row in range(0, height, rows)]
        compositor = Compositor(width, height)
        guides = Compositor(width, height, channels=6) if options.denoise else None
        tiles, waited = [], 0.0
        started = time.perf_counter()
        with CyclesWindowRenderer(scene, options.seed, guides=options.denoise) as renderer:
            for index, band in enumerate(bands):
                paused = time.perf_counter()
                yield index / len(bands), f"gold: band {index + 1}/{len(bands)} ({options.max_spp} spp)"
                waited += time.perf_counter() - paused
                if len(bands) == 1:
                    window, rendered = band, renderer.render(None, options.max_spp)
                else:
                    window = render_window(band, EXACT_MARGIN, width, height)
                    rendered = renderer.render(window, options.max_spp)
                compositor.add(band, crop(rendered.pixels, window, band), options.max_spp)
                if guides is not None:
                    guides.add(band, crop(rendered.guides, window, band), options.max_spp)
                tiles.append(tile_entry(band, rendered) | {"window": list(window)})
        phases = {"maps": 0.0, "renders": time.perf_counter() - started - waited}
        image, samples = compositor.result()
        image, denoise_guides, non_finite = finish_image(
            image, None if guides is None else guides.result()[0], options, phases, guide_prefilter(scene))
        stats = render_stats("gold", scene, options, width, height, samples, phases, tiles, warnings,
                             renderer.sync_seconds, denoise_guides, non_finite)
    stats.bands = {"rows": rows, "count": len(bands), "margin": EXACT_MARGIN,
                      "note": "bit-identical to one full-frame render; the wall time includes "
                              "the margin rows"}
    yield 1.0, "gold: done"
    return RenderOutcome(image, samples, stats, warnings)
