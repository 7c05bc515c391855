"""The knobs of a selective render, checked before any scene is opened.

Section 5 of the paper: the maximum number of rays per pixel is a user parameter and the
director map weights it per pixel. Cycles takes one sample count per render, so the frame is
cut into tiles (``core.sampling.tile_plan``); these options say how.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ..checks import frame_size, parse_frame_size
from ..errors import Field, SettingError
from ..option_table import DEFAULTS, OPTIONS
from .volume_estimator import EstimatorChoice, check_estimator, fixed_choice

#: The per-pixel ceiling of a guided render asked for none: far above any budget's reach on a
#: CPU, and well inside what Cycles accepts (2^24 samples).
UNBOUNDED_SPP = 1 << 16
#: Blender 5's volume scattering probability guiding denoises its guide buffers with an
#: 11-tap Gaussian (radius 5 px) in two passes; a margin of twice that radius makes a tile
#: bit-identical to the same pixels of a full-frame render (see tests/test_selective_render.py).
EXACT_MARGIN = 10


@dataclass(frozen=True)
class RenderOptions:
    """How a selective render spends its samples.

    Parameters
    ----------
    max_spp
        The ceiling: samples per pixel where the director map is 1 (the gold standard's count);
        the most any pixel of a guided render gets (``UNBOUNDED_SPP``: no ceiling asked for).
    min_spp
        The floor: every pixel gets at least this many samples (a pixel with none is black).
    tile_size
        Edge of the square tiles the plan starts from, in pixels (split down to 8 where it pays).
    tile_quantile
        Which quantile of a tile's per-pixel targets the tile renders with; 1.0 (the maximum)
        means no pixel ever gets fewer samples than the map asks for.
    spp_levels
        0 keeps every integer sample count. N >= 2 rounds each tile's count *up* to one of N
        geometrically spaced levels between min_spp and max_spp, so more neighbours share a
        count and merge into fewer, larger renders (at the price of extra samples).
    seed
        Cycles' seed for every render, so a rectangle always renders to the same pixels.
    margin
        Extra pixels rendered around each rectangle and cropped away. Cycles' pixel filter
        is importance-sampled (a pixel only sees its own samples), so 0 is seamless; see
        ``EXACT_MARGIN`` for bit-identity with a full-frame render.
    render_cost
        The fixed cost of one Cycles render (scene update, session reset, image write) in
        pixel-samples: a tile is split into quadrants where that saves more samples than the
        extra renders cost. About 4 ms per render against 2-6 us per pixel-sample of fog on
        two CPU cores (bench/bench_selective.py); a huge value keeps whole tiles.
    adaptive_threshold
        None: every rectangle renders exactly its samples. A number: Cycles' adaptive sampling
        inside each rectangle, its samples as the ceiling and noise threshold
        ``adaptive_threshold / sqrt(spp / max_spp)`` (looser where the map is low, in step with
        the noise the plain plan would leave there).
    resolution
        (width, height) to render at instead of the scene's own (percentage taken as 100).
    denoise
        Denoise the finished frame with Open Image Denoise (Cycles' own denoiser), guided by
        albedo and normal passes, the same way in every mode; tiles are never denoised one
        by one (that would seam). ``addon.cycles.denoise`` says why this is on by default.
    estimator, step_rate
        How Cycles estimates the volumes (``core.sampling.volume_estimator``): scene,
        unbiased, biased (at ``step_rate``, default the scene's) or auto.
    estimator_choice
        What auto chose for this scene and frame (``addon.maps.estimator_choice``); a render
        with auto and no choice is refused.
    """

    max_spp: int
    min_spp: int = DEFAULTS["min_spp"]
    tile_size: int = DEFAULTS["tile_size"]
    tile_quantile: float = DEFAULTS["tile_quantile"]
    spp_levels: int = DEFAULTS["spp_levels"]
    seed: int = DEFAULTS["seed"]
    margin: int = DEFAULTS["margin"]
    render_cost: int = DEFAULTS["render_cost"]
    adaptive_threshold: float | None = DEFAULTS["adaptive_threshold"]
    resolution: tuple[int, int] | None = None
    denoise: bool = DEFAULTS["denoise"]
    estimator: str = "scene"
    step_rate: float | None = DEFAULTS["step_rate"]
    estimator_choice: EstimatorChoice | None = None

    def check(self) -> "RenderOptions":
        """Raise InputError naming the first impossible option; return self. Each value is
        checked against its option (``core.option_table``), then what relates them."""
        for name in ("max_spp", "min_spp", "tile_size", "tile_quantile", "spp_levels", "seed", "margin",
                     "render_cost", "adaptive_threshold", "denoise"):
            OPTIONS[name].check(getattr(self, name))
        if self.min_spp > self.max_spp:
            raise SettingError("{min_spp} is larger than {max_spp}",
                               min_spp=self.min_spp, max_spp=self.max_spp)
        if self.spp_levels == 1:
            raise SettingError("{spp_levels.name} must be 0 (off) or at least 2 "
                               "(got {spp_levels.value})", spp_levels=self.spp_levels)
        if self.resolution is not None:
            frame_size(*self.resolution, Field("resolution"))
        check_estimator(self.estimator, self.step_rate)
        return self

    @property
    def has_ceiling(self) -> bool:
        """False for a guided render asked for no ceiling (``UNBOUNDED_SPP``)."""
        return self.max_spp < UNBOUNDED_SPP

    def volume_estimator(self) -> EstimatorChoice:
        """What the renders use for volumes: auto's choice, or the fixed one asked for."""
        if self.estimator_choice is not None:
            return self.estimator_choice
        if self.estimator == "auto":
            # Our bug, not the user's: the front end skipped the choice.
            raise ValueError("estimator 'auto' must be chosen for the scene before rendering "
                             "(addon.maps.estimator_choice)")
        return fixed_choice(self.estimator, self.step_rate)

    def noise_threshold(self, spp: int) -> float | None:
        """Cycles' noise threshold for a rectangle of ``spp`` samples (None without
        per-rectangle adaptive sampling): ``adaptive_threshold / sqrt(spp / max_spp)``, looser
        where the map asked for fewer samples."""
        if self.adaptive_threshold is None:
            return None
        return self.adaptive_threshold / math.sqrt(spp / self.max_spp)

    def check_frame(self, width: int, height: int) -> None:
        """Raise InputError when the tiles do not fit the frame they are cut from."""
        if self.tile_size > max(width, height):
            raise SettingError(f"{{tile_size}} is larger than the {width}x{height} frame",
                               tile_size=self.tile_size)

    def to_dict(self) -> dict:
        data = asdict(self)
        data["resolution"] = list(self.resolution) if self.resolution else None
        data["estimator_choice"] = (None if self.estimator_choice is None
                                    else self.estimator_choice.to_dict())
        return data


def parse_resolution(text: str) -> tuple[int, int]:
    """'512x288' -> (512, 288); InputError for anything else, and for sizes Blender cannot
    render here (``core.checks.frame_size``)."""
    return parse_frame_size(text)
