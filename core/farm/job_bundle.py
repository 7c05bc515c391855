"""A job bundle on disk: the folder layout AWS Deadline Cloud submits and ``openjd`` runs.

``template.yaml``, ``parameter_values.yaml``, ``asset_references.yaml`` (the files the scene
reads), ``worker_requirements.txt`` (the pinned versions a worker installs), our marker
``xsl_render_bundle.json`` and, by default, ``output/``. The folder is ours to write when it
does not exist, is empty or holds our marker, so a typo in --bundle never overwrites someone's
files; an existing bundle of ours is rewritten in place and its output kept, so a rerun of the
job skips every task whose results are still current."""
from __future__ import annotations

import time
from pathlib import Path

from ..errors import SettingError
from ..files import output_set, write_json, write_text
from .assets import FILE_NAME as ASSET_REFERENCES
from .worker_requirements import FILE_NAME as WORKER_REQUIREMENTS

MARKER = "xsl_render_bundle.json"
TEMPLATE = "template.yaml"
PARAMETER_VALUES = "parameter_values.yaml"


def check_bundle_folder(folder: str | Path) -> Path:
    """``folder`` if a bundle may be written there; InputError (one line) otherwise."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise SettingError("{bundle} exists and is not a folder", bundle=folder)
    if folder.is_dir() and any(folder.iterdir()) and not (folder / MARKER).is_file():
        raise SettingError(f"{{bundle}} is not empty and is not an xsl-render job bundle "
                           f"(no {MARKER}); refusing to overwrite it", bundle=folder)
    return folder


def _yaml(data: dict) -> str:
    import yaml     # PyYAML: pinned with openjd-cli (requirements.lock)

    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True, width=100)


def write_bundle(folder: str | Path, template: dict, values: dict, summary: dict,
                 assets: dict | None = None, requirements: str | None = None) -> list[Path]:
    """Write the bundle's files, all together or none (``core.files.output_set``);
    ``assets`` and ``requirements`` when given (a bundle of an earlier format lacks them)."""
    folder = check_bundle_folder(folder)
    marker = {"generator": "xsl-render farm", "format": 2,
              "written": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), **summary}
    with output_set():
        written = [write_json(folder / MARKER, marker),
                   write_text(folder / TEMPLATE, _yaml(template)),
                   write_text(folder / PARAMETER_VALUES, _yaml(values))]
        if assets is not None:
            written.append(write_text(folder / ASSET_REFERENCES, _yaml(assets)))
        if requirements is not None:
            written.append(write_text(folder / WORKER_REQUIREMENTS, requirements))
        return written
