"""The validation's files on disk, so that a run killed midway continues where it stopped.

``DIR/results.json`` (every number, rewritten as runs finish), ``DIR/report.html``, and per
scene its maps (``maps/``, ``maps_no_minbound/``), each run's ``<variant>.exr``,
``_spp.exr/.png`` and ``<variant>.json`` record (inputs, their hash, stats, metrics) and its
heatmaps. A record is written last, after the images it describes, every file through a
temporary name; a finished step is reused while the hash of its inputs is the one stored."""
from __future__ import annotations

import json
import os
from pathlib import Path

from ..checks import writable_folder
from ..files import file_sha256, json_digest, write_json

#: Bumped when a change to the pipeline makes old renders or metrics incomparable.
PIPELINE_VERSION = 1


def inputs_hash(inputs: dict) -> str:
    """A stable hash of JSON-ready inputs (keys sorted, floats as JSON writes them)."""
    return json_digest({"pipeline": PIPELINE_VERSION, **inputs})


def read_record(path: str | os.PathLike, expected_hash: str, needs: tuple[Path, ...] = ()) -> dict | None:
    """The record at ``path`` if it was made from inputs with ``expected_hash`` and every file
    in ``needs`` exists; None otherwise (missing, stale, unreadable: the step runs again)."""
    path = Path(path)
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("input_hash") != expected_hash:
        return None
    if not all(Path(p).is_file() for p in needs):
        return None
    return record


def write_record(path: str | os.PathLike, record: dict) -> Path:
    return write_json(path, record)


def check_output_folder(folder: str | os.PathLike, label: str = "--out") -> Path:
    """InputError (one line) unless ``folder`` is, or can become, a writable folder
    (``label`` names it in the message)."""
    return writable_folder(folder, name=label)
