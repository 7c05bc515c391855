"""What a validation renders per scene (paper sections 5 and 6.1), and the runs the paper
does not have: each compared with the converged reference and, as the paper does, with the
gold standard (the ceiling in every pixel, the file's own settings).

The paper's versions: X only, S only, XS, XSL (road also without MinBound). Ours: uniform at
1/8, 1/4 and 1/2 of the ceiling (with gold, the file's time-quality curve); uniform, Cycles'
adaptive and ``guided`` in the XSL run's time; and Auto Volumes (``--estimator auto``) at the
file's samples and in the file's time (gold's), the project's main job.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..checks import name_list
from ..errors import Field, SettingError
from ..maps.options import MapOptions

GOLD = "gold"
#: The run whose wall time (maps included) the equal-time baselines get.
EQUAL_TIME_SOURCE = "xsl"
#: How many times the ceiling Auto Volumes may render in the file's time: a time-limited render
#: stops at Cycles' limit, and at the ceiling would stop early (auto renders it sooner).
AUTO_CEILING_FACTOR = 4


@dataclass(frozen=True)
class Variant:
    """One image of a scene.

    Attributes
    ----------
    name : file stem and key in results.json.
    label : what the report calls it (the paper's notation where it has one).
    kind : "gold", "selective", "uniform", "adaptive", "guided" or "auto" (uniform with
        ``--estimator auto``, the way Auto Volumes renders the file).
    director : for selective runs, "xs" or "xsl": which combination of the maps directs it.
    map_options : the weights and operators of that combination and whether X uses MinBound.
    spp_fraction : for a uniform or auto run with samples of its own, the fraction of the
        ceiling it renders everywhere (None: a run at ``time_of``'s time).
    time_of : the run whose render time an equal-time run gets (the XSL run unless named).
    """

    name: str
    label: str
    kind: str
    director: str | None = None
    map_options: MapOptions | None = None
    spp_fraction: float | None = None
    time_of: str | None = None

    @property
    def equal_time(self) -> bool:
        return self.kind in EQUAL_TIME_KINDS and self.spp_fraction is None

    @property
    def time_source(self) -> str | None:
        """The run whose time an equal-time run gets (None for the others)."""
        return (self.time_of or EQUAL_TIME_SOURCE) if self.equal_time else None

    def spp(self, ceiling: int) -> int:
        """Samples per pixel of a uniform run with ``spp_fraction`` (at least 1)."""
        return max(1, round(ceiling * self.spp_fraction))

    def to_dict(self) -> dict:
        data = {"name": self.name, "label": self.label, "kind": self.kind, "director": self.director,
                "map_options": self.map_options.to_dict() if self.map_options else None}
        if self.spp_fraction is not None:       # absent otherwise: older runs' hashes stay valid
            data["spp_fraction"] = self.spp_fraction
        if self.time_of is not None:
            data["time_of"] = self.time_of
        return data


#: Kinds of run given another run's wall time (without samples of their own).
EQUAL_TIME_KINDS = ("uniform", "adaptive", "guided", "auto")

_PAPER = MapOptions()
VARIANTS = {
    v.name: v for v in (
        Variant(GOLD, "Gold standard", "gold"),
        Variant("auto_file_samples", "Auto Volumes, the file's samples", "auto", spp_fraction=1.0),
        Variant("auto_equal_time", "Auto Volumes, the file's time", "auto", time_of=GOLD),
        Variant("x_only", "X only: XS(1, 0, +)", "selective", "xs", MapOptions(wx=1.0, ws=0.0)),
        Variant("s_only", "S only: XS(0, 1, +)", "selective", "xs", MapOptions(wx=0.0, ws=1.0)),
        Variant("xs", "XS(0.5, 0.5, +)", "selective", "xs", _PAPER),
        Variant("xsl", "XSL(0.5, 0.5, +)", "selective", "xsl", _PAPER),
        Variant("xsl_no_minbound", "XSL without MinBound", "selective", "xsl",
                MapOptions(minbound=False)),
        Variant("uniform_eighth", "Uniform, 1/8 of the ceiling", "uniform", spp_fraction=1 / 8),
        Variant("uniform_quarter", "Uniform, 1/4 of the ceiling", "uniform", spp_fraction=1 / 4),
        Variant("uniform_half", "Uniform, 1/2 of the ceiling", "uniform", spp_fraction=1 / 2),
        Variant("uniform_equal_time", "Uniform, XSL's time", "uniform"),
        Variant("adaptive_equal_time", "Cycles adaptive, XSL's time", "adaptive"),
        Variant("guided_equal_time", "Guided (auto), XSL's time", "guided"),
    )
}
#: The main job's comparison: the file as it renders (gold: its samples, its settings) and
#: Auto Volumes in the same time.
FILE_RUN, AUTO_RUN = GOLD, "auto_equal_time"
#: Every variant but the MinBound comparison, which only some scenes get.
DEFAULT_VARIANTS = ("gold", "auto_file_samples", "auto_equal_time", "x_only", "s_only", "xs", "xsl",
                    "uniform_eighth", "uniform_quarter", "uniform_half", "uniform_equal_time",
                    "adaptive_equal_time", "guided_equal_time")
#: The uniform runs with samples of their own: with gold, the uniform time-quality curve.
UNIFORM_CURVE_VARIANTS = ("uniform_eighth", "uniform_quarter", "uniform_half")
#: Scenes that also get XSL without MinBound (the paper's road scene, the one with sky).
DEFAULT_MINBOUND_SCENES = ("road",)


def parse_variants(text: str | None) -> tuple[str, ...]:
    """'gold,xs,xsl' -> the variants in plan order; the gold standard is always in (every
    metric compares with it), and equal-time runs bring the XSL run they take their time from."""
    if text is None:
        return DEFAULT_VARIANTS
    names = name_list(text, Field("variants"), VARIANTS, "variant")
    wanted = {GOLD, *names}
    wanted |= {VARIANTS[name].time_source for name in names} - {None}
    return tuple(name for name in VARIANTS if name in wanted)


def scene_variants(variants: tuple[str, ...], compare_minbound: bool = False) -> list[Variant]:
    """The variants one scene renders, in order: gold first, selective runs, then the
    equal-time baselines (which need the XSL run's time). ``compare_minbound`` adds XSL
    without MinBound when XSL is rendered."""
    names = set(variants)
    if compare_minbound and EQUAL_TIME_SOURCE in names:
        names.add("xsl_no_minbound")
    return [variant for name, variant in VARIANTS.items() if name in names]


def maps_needed(variant: Variant) -> tuple[str, ...]:
    """The maps a selective run waits for, so its time counts only what it uses (Fig. 8
    includes map generation): S is computed from the snapshot and the inverted X map."""
    options = variant.map_options
    if variant.kind != "selective" or options is None:
        return ()
    needed = ["x"]
    if options.ws > 0 or variant.director == "xsl":
        needed += ["snapshot", "s"]
    needed.append("xs")
    if variant.director == "xsl":
        needed += ["l", "xsl"]
    return tuple(needed)


def map_seconds(variant: Variant, seconds: dict) -> float:
    """Seconds the maps of ``variant`` took, from the per-map seconds of maps.json."""
    return float(sum(float(seconds.get(name, 0.0)) for name in maps_needed(variant)))


def scaled_size(size: tuple[int, int], longest_side: int | None) -> tuple[int, int]:
    """``size`` scaled (aspect kept, rounded) so that its longer side is ``longest_side``."""
    width, height = size
    if longest_side is None:
        return width, height
    scale = longest_side / max(width, height)
    return max(1, round(width * scale)), max(1, round(height * scale))


def parse_list(text: str | None, default: tuple[str, ...]) -> tuple[str, ...]:
    """'a,b' -> ('a', 'b'); None -> default."""
    if text is None:
        return default
    return tuple(item.strip() for item in text.split(",") if item.strip())


@dataclass(frozen=True)
class ValidationSettings:
    """The knobs of one validation run (the paper: 16 spp ceiling, 512 px on the longer side).

    ``resolution`` renders every scene at that size; else ``longest_side`` scales each scene's
    own resolution to that many pixels on its longer side (the paper's "512 pixels in their
    largest side"); with neither, each scene renders at its own. ``vdp`` False reports VDP as
    skipped (it is slow, and optional anyway). ``denoise`` denoises every finished frame, gold
    and the others alike (``RenderOptions.denoise``).
    """

    max_spp: int = 16
    resolution: tuple[int, int] | None = None
    longest_side: int | None = None
    min_spp: int = 1
    tile_size: int = 32
    seed: int = 0
    vdp: bool = True
    denoise: bool = True
    variants: tuple[str, ...] = DEFAULT_VARIANTS
    reference_spp: int | None = None

    def render_options(self, max_spp: int | None = None):
        """The RenderOptions of every render (``max_spp`` overrides the ceiling for one scene).
        InputError as well for a seed the converged reference uses, or its samples below 1."""
        from ..sampling.render_options import RenderOptions
        from .reference import REFERENCE_SEED, check_contestant_seeds

        if self.longest_side is not None and not 8 <= self.longest_side <= 16384:
            raise SettingError("{longest_side.name} must be between 8 and 16384 pixels "
                               "(got {longest_side.value})", longest_side=self.longest_side)
        if self.reference_spp is not None and self.reference_spp < 1:
            raise SettingError("{reference_spp.name} must be at least 1 (got {reference_spp.value})",
                               reference_spp=self.reference_spp)
        check_contestant_seeds((self.seed,), REFERENCE_SEED)
        return RenderOptions(max_spp=max_spp or self.max_spp, min_spp=self.min_spp,
                             tile_size=self.tile_size, seed=self.seed,
                             resolution=self.resolution, denoise=self.denoise).check()

    def to_dict(self) -> dict:
        return {"max_spp": self.max_spp, "resolution": list(self.resolution) if self.resolution else None,
                "longest_side": self.longest_side,
                "min_spp": self.min_spp, "tile_size": self.tile_size, "seed": self.seed,
                "vdp": self.vdp, "denoise": self.denoise, "variants": list(self.variants),
                "reference_spp": self.reference_spp}
