"""Which of Cycles' sample patterns an ``--estimator auto`` run renders with.

Blender 5 gives a new file blue noise (``'AUTOMATIC'``: Cycles' "pure" blue-noise pattern for
a final render). A file saved before Blender 4.2 is versioned to the old default, Tabulated
Sobol (``'TABULATED_SOBOL'``), which the interface shows only with the debug options, so an
artist cannot see that the file renders with it. Both are unbiased; blue noise leaves its
noise at high spatial frequencies, where the eye sees it least, which is the paper's idea
applied to where a sample's error lands. Measured against the converged references at 16
spp: uniform with the files' own settings, medians of 3 (``bench/bench_sample_pattern.py``,
``docs/bench_sample_pattern.txt``), mean FLIP road 0.0440 against 0.0449, balls_a 0.0464
against 0.0509, balls_b 0.0611 against 0.0744, statue 0.0511 against 0.0529, the renders
0-37 % faster; with auto's volume estimator (by hand, seeds 0-2; balls_b 0-1, road 0-3)
balls_a 0.0376 against 0.0410, statue 0.0442 against 0.0454, balls_b 0.0505 against
0.0522, road 0.0400 against 0.0404. So auto renders a file that carries the old pattern
with Blender 5's, and leaves every other pattern (chosen on purpose through the debug
options) as it is.

Blue noise is at its best at a power of two samples, as Tabulated Sobol is, and falls further
between them (balls_a, 18-20 spp: mean FLIP 0.047 against 16's 0.038), which the guided
sampler's rounding (``sample_counts.sobol_friendly``) and its one count per frame
(``sample_counts.column_count``) avoid.
"""
from __future__ import annotations

#: The pattern Blender 5 gives a new file (blue noise for a final render).
BLENDER_DEFAULT = "AUTOMATIC"
#: The pattern files from before Blender 4.2 are versioned to.
LEGACY = "TABULATED_SOBOL"


def auto_sample_pattern(scene_pattern: str) -> str | None:
    """The pattern auto renders a scene whose own is ``scene_pattern`` with: Blender 5's
    default in place of the legacy one, else None (the scene's own)."""
    return BLENDER_DEFAULT if scene_pattern == LEGACY else None
