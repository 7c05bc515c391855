#!/usr/bin/env python3
"""Set up and run xsl_render from nothing: ``python3 run.py build``, ``demo`` or ``test``.

On first use (and whenever requirements.lock or pyproject.toml change) it creates ``.venv``,
installs the pinned versions and the project itself (the ``xsl-render`` command), then:

    build [ARGS...]  the extension's zips, one per platform, in dist/ (tools/build_extension.py)
    demo [ARGS...]   the main job on the bundled road scene
    test [ARGS...]   the suite: pytest on every core, then the tests marked timing alone;
                     with ARGS, one ``pytest ARGS`` run

Standard library only, so any Python 3.11 runs it."""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
STAMP = VENV / ".xsl-installed"
INPUTS = ("requirements.lock", "pyproject.toml")


def venv_bin(name: str) -> Path:
    folder = "Scripts" if os.name == "nt" else "bin"
    suffix = ".exe" if os.name == "nt" else ""
    return VENV / folder / f"{name}{suffix}"


def wanted_stamp() -> str:
    digest = hashlib.sha256()
    for name in INPUTS:
        digest.update((ROOT / name).read_bytes())
    return digest.hexdigest()


def ensure_venv() -> None:
    if sys.version_info[:2] != (3, 11):
        sys.exit(f"run.py: Python 3.11 is needed (bpy 5.0 is built for it); this is {sys.version.split()[0]}")
    stamp = wanted_stamp()
    if STAMP.exists() and STAMP.read_text() == stamp and venv_bin("xsl-render").exists():
        return
    if not venv_bin("python").exists():
        print("run.py: creating .venv", file=sys.stderr)
        subprocess.check_call([sys.executable, "-m", "venv", str(VENV)])
    python = str(venv_bin("python"))
    print("run.py: installing pinned packages from requirements.lock", file=sys.stderr)
    pip = [python, "-m", "pip", "--disable-pip-version-check", "-q"]
    subprocess.check_call(pip + ["install", "-r", str(ROOT / "requirements.lock")])
    # --no-deps: every dependency is pinned in the lock file, not in pyproject.toml.
    subprocess.check_call(pip + ["install", "--no-deps", "--no-build-isolation", "-e", str(ROOT)])
    STAMP.write_text(stamp)


def ensure_browser() -> None:
    """The report and experiment-page tests drive a headless Chromium. Debian's package is
    the only browser reachable without the open internet; install it when we can."""
    if shutil.which("chromium") or os.name == "nt" or not shutil.which("apt-get"):
        return
    if hasattr(os, "geteuid") and os.geteuid() != 0:
        print("run.py: chromium not found (apt-get install chromium); browser tests will skip",
              file=sys.stderr)
        return
    print("run.py: installing Debian's chromium for the browser tests", file=sys.stderr)
    quiet = {"stdout": subprocess.DEVNULL, "env": {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}}
    if subprocess.call(["apt-get", "update", "-q"], **quiet) == 0:
        subprocess.call(["apt-get", "install", "-y", "-q", "--no-install-recommends",
                         "chromium", "chromium-driver"], **quiet)


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in ("build", "demo", "test"):
        print(__doc__, file=sys.stderr)
        return 2
    ensure_venv()
    job, rest = argv[0], argv[1:]
    if job == "build":
        command = [str(venv_bin("python")), str(ROOT / "tools" / "build_extension.py"), *rest]
    elif job == "demo":
        command = [str(venv_bin("xsl-render")), "demo", *rest]
    else:
        ensure_browser()
        pytest = [str(venv_bin("python")), "-m", "pytest"]
        if not rest:
            return whole_suite(pytest)
        command = [*pytest, *rest]
    return subprocess.call(command, cwd=ROOT)


def whole_suite(pytest: list[str]) -> int:
    """The suite in two runs: every test but the timed ones on as many workers as there are
    cores (at most 4; most tests wait on one thread: Blender's start-up, files, other
    processes), then the tests marked ``timing`` alone, since they measure the wall clock
    (a time budget kept, a cache hit) and a second worker's renders would slow them."""
    workers = str(max(1, min(4, os.cpu_count() or 1)))
    parallel = subprocess.call([*pytest, "-n", workers, "-m", "not timing"], cwd=ROOT)
    alone = subprocess.call([*pytest, "-m", "timing"], cwd=ROOT)
    return parallel or alone


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
