"""The converged reference every quality figure is measured against: its defaults, its cache key
and where cached references are kept (the Blender side is ``addon.validation.reference``).

A reference is a uniform render with far more samples than any contestant, a seed no
contestant uses, denoised as every run is. It takes minutes, so each is kept under the hash of
what decides its pixels (the .blend's bytes, scene, frame, resolution, samples, seed, Blender
and denoiser versions), looked up first in ``example_blends/references/`` (shipped: the demo's
road) and then in the user cache (``$XSL_RENDER_CACHE``, else ``$XDG_CACHE_HOME/xsl_render``,
else ``~/.cache/xsl_render``). An entry is ``<key>.exr`` and ``<key>.json``, the JSON written
last, so an entry with a JSON is whole."""
from __future__ import annotations

import os
import shutil
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..errors import SettingError
from ..files import atomic_path, output_set
from ..imageio import image_attributes, read_image, write_exr
from .example_scenes import example_folders
from .store import inputs_hash, read_record, write_record

#: The reference's seed. Contestants use seeds 0, 1, 2, ...; one that used this seed would
#: share the reference's samples and look better than it is.
REFERENCE_SEED = 7
#: The reference gets SPP_PER_CEILING x the contestants' ceiling, and never fewer than
#: MIN_REFERENCE_SPP samples per pixel.
MIN_REFERENCE_SPP = 1024
SPP_PER_CEILING = 16
#: The folder (under the cache root, and under example_blends/) that holds references.
FOLDER = "references"
#: Header attributes of a reference EXR, so that a reference file given on its own still
#: says which seed and samples made it.
SEED_ATTRIBUTE = "xsl_render:reference_seed"
SPP_ATTRIBUTE = "xsl_render:reference_spp"
KEY_ATTRIBUTE = "xsl_render:reference_key"


def default_reference_spp(ceiling: int) -> int:
    """Samples per pixel of the reference for contestants with ``ceiling`` at most:
    ``max(1024, 16 x ceiling)``."""
    if ceiling < 1:
        raise SettingError("{ceiling.name} must be at least 1 (got {ceiling.value})", ceiling=ceiling)
    return max(MIN_REFERENCE_SPP, SPP_PER_CEILING * int(ceiling))


def check_reference_options(spp: int | None, seed: int) -> None:
    """InputError (one line) for a reference sample count below 1 or a negative seed."""
    if spp is not None and spp < 1:
        raise SettingError("{spp.name} must be at least 1 (got {spp.value})", spp=spp)
    if seed < 0:
        raise SettingError("{seed.name} must not be negative (got {seed.value})", seed=seed)


def check_contestant_seeds(seeds, reference_seed: int | None) -> None:
    """InputError when a contestant would render with the reference's own seed: it would
    share the reference's first samples, and its error would be too small."""
    if reference_seed is None:
        return
    for seed in seeds:
        if int(seed) == int(reference_seed):
            raise SettingError(f"contestant seed {seed} is the converged reference's seed; give "
                               "contestants other seeds (or the reference another {seed.name})",
                               seed=reference_seed)


@dataclass(frozen=True)
class ReferenceInputs:
    """Everything that decides a reference's pixels; ``key`` is their hash."""

    blend_sha256: str
    scene: str
    frame: int
    resolution: tuple[int, int]
    spp: int
    seed: int
    blender: str            # bpy.app.version_string
    denoise: str            # addon.cycles.denoise.DENOISE_VERSION

    def to_dict(self) -> dict:
        data = asdict(self)
        data["resolution"] = list(self.resolution)
        return data

    @classmethod
    def from_dict(cls, data: dict) -> "ReferenceInputs":
        return cls(**{**data, "resolution": tuple(data["resolution"])})

    @property
    def key(self) -> str:
        return inputs_hash({"step": "reference", **self.to_dict()})


@dataclass(frozen=True)
class CachedReference:
    """A reference found on disk: its image file, its record, and which cache held it."""

    path: Path
    record: dict
    source: str             # "shipped" or "cache"


def cache_root(environ=None) -> Path:
    """The user cache: $XSL_RENDER_CACHE, else $XDG_CACHE_HOME/xsl_render, else
    ~/.cache/xsl_render."""
    environ = os.environ if environ is None else environ
    if environ.get("XSL_RENDER_CACHE"):
        return Path(environ["XSL_RENDER_CACHE"]).expanduser()
    if environ.get("XDG_CACHE_HOME"):
        return Path(environ["XDG_CACHE_HOME"]).expanduser() / "xsl_render"
    return Path.home() / ".cache" / "xsl_render"


def user_folder(environ=None) -> Path:
    """Where references rendered here are kept."""
    return cache_root(environ) / FOLDER


def shipped_folders() -> list[Path]:
    """The references shipped with the source tree (example_blends/references/)."""
    return [folder / FOLDER for folder in example_folders()]


def entry_paths(folder: str | os.PathLike, key: str) -> tuple[Path, Path]:
    """The image and record of the entry ``key`` in ``folder``."""
    folder = Path(folder)
    return folder / f"{key}.exr", folder / f"{key}.json"


def find_reference(key: str, environ=None) -> CachedReference | None:
    """The cached reference with this key, shipped entries first; None when there is none."""
    places = [(folder, "shipped") for folder in shipped_folders()] + [(user_folder(environ), "cache")]
    for folder, source in places:
        image, record_path = entry_paths(folder, key)
        record = read_record(record_path, key, (image,))
        if record is not None:
            return CachedReference(image, record, source)
    return None


@dataclass(frozen=True)
class ReferenceRun:
    """What a reference's cache record says about its render: the uniform run's statistics
    (the part kept) and the seconds of the whole reference (scene opening to denoised)."""

    render: dict
    seconds: float | None = None

    #: The run's statistics a cache record keeps.
    KEPT = ("mode", "resolution", "seed", "wall_s", "phases_s", "mean_spp", "total_samples",
            "cycles_sync_s")

    @property
    def cycles_sync_s(self) -> float:
        return float(self.render.get("cycles_sync_s") or 0.0)

    def to_json(self) -> dict:
        return {**self.render, "reference_wall_s": self.seconds}

    @classmethod
    def from_json(cls, data: dict) -> "ReferenceRun":
        data = dict(data or {})
        return cls(data, data.pop("reference_wall_s", None))


def write_reference(folder: str | os.PathLike, inputs: ReferenceInputs, image: np.ndarray,
                    run: ReferenceRun, file_name: str | None = None) -> CachedReference:
    """Write the entry for ``inputs`` into ``folder``: the EXR first, the record last.
    ``file_name`` (the .blend's name) is kept in the record for people, not in the key."""
    exr, record_path = entry_paths(folder, inputs.key)
    record = {"input_hash": inputs.key, "file": file_name, "inputs": inputs.to_dict(),
              "stats": run.to_json()}
    # A set of its own, even inside a command's: the entry is read back at once (the
    # reference command copies it) and outlives the command as a cache entry.
    with output_set(own=True):
        write_exr(exr, image, attributes={SEED_ATTRIBUTE: inputs.seed, SPP_ATTRIBUTE: inputs.spp,
                                          KEY_ATTRIBUTE: inputs.key})
        write_record(record_path, record)
    return CachedReference(exr, record, "cache")


def copy_file(source: str | os.PathLike, target: str | os.PathLike) -> Path:
    """Copy ``source`` to ``target`` through a temporary name (never half a file)."""
    with atomic_path(target) as tmp:
        shutil.copyfile(source, tmp)
    return Path(target)


@dataclass(frozen=True)
class ReferenceImage:
    """A reference read from a file: its pixels and, when its header says, its seed and
    samples (None for an EXR that did not come from ``xsl-render reference``)."""

    path: Path
    image: np.ndarray
    seed: int | None
    spp: int | None
    key: str | None


def read_reference(path: str | os.PathLike, size: tuple[int, int] | None = None) -> ReferenceImage:
    """Read a reference EXR; InputError when it is not an .exr or, given ``size`` (width,
    height), when it has another size."""
    path = Path(path)
    if path.suffix.lower() != ".exr":
        raise SettingError("{reference.name} must be an .exr file (got {reference.value})",
                           reference=path)
    image = read_image(path)
    if size is not None and (image.shape[1], image.shape[0]) != tuple(size):
        raise SettingError(f"{{reference}} is {image.shape[1]}x{image.shape[0]}, the runs render "
                           f"at {size[0]}x{size[1]}", reference=path)
    attributes = image_attributes(path)

    def number(name):
        value = attributes.get(name)
        return None if value is None else int(value)
    key = attributes.get(KEY_ATTRIBUTE)
    return ReferenceImage(path, image, number(SEED_ATTRIBUTE), number(SPP_ATTRIBUTE),
                          None if key is None else str(key))
