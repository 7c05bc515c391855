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
0.0522, road 0.0400 against 0.0404.

Auto renders blue noise with its sequence rounded up to a power of two (Cycles' own
"Blue-Noise (round)", ``ROUND``). Cycles lays the pure pattern's sequence out by the render's
sample count: at a power of two it is the same pattern, the same pixels, but at any other
count each pixel's samples are a window of the sequence that no longer lines up with its
power-of-two strata. After OIDN that can cost a scene dearly: balls_a's denoising guides
came out 6-25x noisier at 12-28 spp than at 16 (the floor keeps a speckle the denoiser
leaves), mean FLIP at 12 / 20 / 24 / 28 spp 0.0486 / 0.0352 / 0.0326 / 0.0323 against 16's
0.0276, where the rounded sequence gives 0.0329 / 0.0284 / 0.0262 / 0.0253; on road, statue
and balls_b, where the pure pattern has no such cliff, the rounded one measured 0-4 % more
FLIP at those counts (``bench/bench_round_counts.py``, ``docs/bench_round_counts.txt``).
Auto renders powers of two where it can (``sample_counts``), but a guided pass's columns and
a range's frames land between them, and the rounded sequence takes away the cliff they fell
off. So auto renders the legacy pattern and Blender 5's blue noise alike with it, and leaves
every other pattern (chosen on purpose through the debug options) as it is.

Cycles honours a debug pattern only while Blender's developer interface and Cycles' debug
options are on (else it renders the pure pattern); the Blender layer turns them on for the
run and puts them back (``addon.cycles.sample_pattern``).
"""
from __future__ import annotations

#: The pattern Blender 5 gives a new file (blue noise for a final render).
BLENDER_DEFAULT = "AUTOMATIC"
#: The pattern files from before Blender 4.2 are versioned to.
LEGACY = "TABULATED_SOBOL"
#: Blue noise, pure (what ``BLENDER_DEFAULT`` renders a final render with, chosen by name).
PURE = "BLUE_NOISE"
#: Blue noise with its sequence rounded up to a power of two: what auto renders with.
ROUND = "BLUE_NOISE_ROUND"
#: The patterns Cycles offers without its debug options; any other needs them.
PLAIN_PATTERNS = frozenset({BLENDER_DEFAULT, LEGACY, PURE})
#: Patterns whose per-pixel sequence Cycles lays out by the session's largest sample count,
#: not the render's own (``session_sequence``): the blue noises (``BLENDER_DEFAULT`` renders
#: the pure one in a final render). The legacy pattern is not among them: measured below.
SESSION_SEQUENCE_PATTERNS = frozenset({BLENDER_DEFAULT, PURE, ROUND, "BLUE_NOISE_FIRST"})


def auto_sample_pattern(scene_pattern: str) -> str | None:
    """The pattern auto renders a scene whose own is ``scene_pattern`` with: the rounded blue
    noise in place of the legacy pattern or the pure blue noise, else None (the scene's own)."""
    return ROUND if scene_pattern in PLAIN_PATTERNS else None


def needs_debug_options(pattern: str) -> bool:
    """Whether Cycles renders ``pattern`` only with its debug options on (otherwise it
    renders the pure blue noise in its place)."""
    return pattern not in PLAIN_PATTERNS


def session_sequence(pattern: str, largest_count: int) -> int:
    """The per-pixel sequence length a render in a Cycles session that already rendered
    ``largest_count`` samples per pixel draws its samples from (0: the render's own count).

    A persistent Cycles session only ever raises the sample count its integrator lays the
    blue noise out by ("unless reset was requested only allow increasing number of samples",
    Cycles' ``Session``; a final render's reset does not ask for it), so with blue noise a
    render of fewer samples than an earlier one in the session takes the first samples of
    each pixel's longer sequence instead of the sequence of its own count: other pixels, and
    worse ones after denoising. Measured (balls_a 256x192, auto's choice, rounded blue noise,
    OIDN, seeds 0-2, every seed alike): 16 spp fresh mean FLIP 0.0375, after a 32-spp render
    0.0413, after 64 0.0423; 8 spp fresh 0.0637, after 16 0.0789 (p95 region FLIP 0.084
    against 0.102). The pure and first-sample blue noises are laid out by the same count in
    Cycles (not measured here). The legacy pattern rendered the same pixels either way. A count at or
    above ``largest_count`` renders what a fresh session renders (checked: 16 after 8, 24
    after 4 and 16)."""
    return int(largest_count) if pattern in SESSION_SEQUENCE_PATTERNS else 0
