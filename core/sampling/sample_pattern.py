"""Which of Cycles' sample patterns an ``--estimator auto`` run renders with.

A new Blender 5 file has blue noise; a file saved before Blender 4.2 is versioned to the
legacy Tabulated Sobol, which the interface shows only with the debug options. Both are
unbiased; blue noise leaves its noise at high spatial frequencies, where the eye sees it
least. Auto renders both with blue noise, its sequence rounded up to a power of two (Cycles'
"Blue-Noise (round)", ``ROUND``): the same pixels at a power of two, and no cliff between
powers of two, where the pure sequence no longer lines up with its strata (docs/performance.md,
"The sample pattern"). Every other pattern, chosen on purpose, is left as it is. Cycles honours
a debug pattern only with its debug options on (``addon.cycles.sample_pattern``)."""
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
