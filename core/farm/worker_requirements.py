"""The pinned requirements a farm worker installs (``worker_requirements.txt`` of a bundle).

A worker set up by the job environment (``WorkerSetup`` pip or conda) gets exactly the
versions the submitting machine runs, since those are the ones its bundle was written and
tested with: the distributions ``xsl-render``'s tasks import (Blender as ``bpy``, numpy,
scipy, scikit-image, OpenImageIO, ...), each with what it requires, at the versions
installed here. In this project's own environment these are requirements.lock's pins
(``run.py`` installs them); from an installed package they are whatever was installed.
A requirement whose marker does not hold here (another platform's) is left to the worker's
pip to resolve, unpinned.
"""
from __future__ import annotations

import re
from importlib import metadata

#: What the farm tasks import (see CONTRIBUTING's layout: core on numpy and scipy, addon on
#: bpy and OpenImageIO). flip-evaluator is for ``compare``, kept so the worker's xsl-render
#: is whole.
TASK_DISTRIBUTIONS = ("bpy", "numpy", "scipy", "scikit-image", "OpenImageIO", "zstandard",
                      "flip-evaluator")
FILE_NAME = "worker_requirements.txt"


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _requirement_names(distribution: metadata.Distribution) -> list[str]:
    """Names ``distribution`` requires here (markers evaluated, extras left out)."""
    from packaging.requirements import Requirement     # pinned with scikit-image (a wheel)

    names = []
    for text in distribution.requires or []:
        requirement = Requirement(text)
        if requirement.marker is None or requirement.marker.evaluate({"extra": ""}):
            names.append(requirement.name)
    return names


def pinned_closure(roots=TASK_DISTRIBUTIONS) -> dict[str, str]:
    """``{name: version}`` of ``roots`` and everything they require, as installed here.

    Raises LookupError naming a root that is not installed (the bundle would pin nothing
    for it, so a worker would not run)."""
    pins: dict[str, str] = {}
    todo = list(roots)
    while todo:
        name = todo.pop()
        key = _canonical(name)
        if key in {_canonical(n) for n in pins}:
            continue
        try:
            distribution = metadata.distribution(name)
        except metadata.PackageNotFoundError:
            if name in roots:
                raise LookupError(f"{name} is not installed here, so a worker's version of it "
                                  "cannot be pinned") from None
            continue                    # an optional dependency nobody installed
        pins[distribution.metadata["Name"]] = distribution.version
        todo.extend(_requirement_names(distribution))
    return dict(sorted(pins.items(), key=lambda item: _canonical(item[0])))


def requirements_text(pins: dict[str, str]) -> str:
    lines = ["# The versions the bundle was written with (xsl-render farm); a worker's",
             "# job environment installs them with pip before the xsl-render package.",
             *(f"{name}=={version}" for name, version in pins.items())]
    return "\n".join(lines) + "\n"
