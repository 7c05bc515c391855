"""Prepare a farm worker to run ``xsl-render`` (the job environment's onEnter action).

Embedded whole in the job template and run by the worker's own Python: standard library only,
nothing of the package (which may not be installed yet). ``--setup none`` checks that
``--executable`` is found; ``pip`` builds a virtual environment (Python 3.11: bpy's wheels are
cp311) with the pinned ``--requirements`` and ``--package``; ``conda`` the same in a conda
environment. An environment is kept in a cache folder named by a digest of what went into it,
built in place under a lock and marked complete last. It talks to the session with Open Job
Description's ``openjd_env``, ``openjd_status`` and ``openjd_progress`` lines."""
from __future__ import annotations

import argparse
import hashlib
import os
import shutil
import signal
import subprocess
import sys
import venv
from pathlib import Path

SETUPS = ("none", "pip", "conda")
PYTHON = (3, 11)
COMPLETE = ".xsl-render-complete"


def say(kind: str, text) -> None:
    print(f"openjd_{kind}: {text}", flush=True)


def fail(text: str) -> None:
    print(f"xsl-render worker setup: {text}", file=sys.stderr, flush=True)
    sys.exit(1)


def default_cache() -> Path:
    if os.name == "nt":
        return Path(os.environ.get("LOCALAPPDATA", Path.home())) / "xsl-render" / "worker-envs"
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "xsl-render" / "worker-envs"


def environment_key(setup: str, requirements: bytes, package: str) -> str:
    """What the environment is made of, as a short digest (its folder's name)."""
    digest = hashlib.sha256(f"{setup}\n{package}\n{sys.platform}\n".encode() + requirements)
    return f"{setup}-{digest.hexdigest()[:16]}"


def bin_folder(prefix: Path, setup: str) -> Path:
    if os.name == "nt":
        return prefix if setup == "conda" else prefix / "Scripts"
    return prefix / "bin"


def env_python(prefix: Path, setup: str) -> Path:
    return bin_folder(prefix, setup) / ("python.exe" if os.name == "nt" else "python")


def run(command: list[str]) -> None:
    print("+ " + " ".join(command), flush=True)
    code = subprocess.call(command)
    if code != 0:
        fail(f"{Path(command[0]).name} failed (exit code {code}): {' '.join(command)}")


class Lock:
    """An exclusive lock on a file: one worker builds an environment, the others wait."""

    def __init__(self, path: Path):
        path.parent.mkdir(parents=True, exist_ok=True)
        self.stream = open(path, "a+b")

    def __enter__(self):
        if os.name == "nt":
            import msvcrt
            self.stream.seek(0)
            while True:
                try:
                    msvcrt.locking(self.stream.fileno(), msvcrt.LK_LOCK, 1)
                    break
                except OSError:
                    continue
        else:
            import fcntl
            fcntl.flock(self.stream.fileno(), fcntl.LOCK_EX)
        return self

    def __exit__(self, *exc):
        self.stream.close()             # closing releases the lock


def build(prefix: Path, setup: str, requirements: Path, package: str) -> None:
    """Make the environment at ``prefix`` (removing a half-built one), install, mark it."""
    if prefix.exists():
        shutil.rmtree(prefix)
    if setup == "pip":
        if sys.version_info[:2] != PYTHON:
            fail(f"--setup pip needs Python {PYTHON[0]}.{PYTHON[1]} (bpy's wheels are cp311); "
                 f"this is {sys.version.split()[0]} at {sys.executable}: set WorkerPython to a "
                 "Python 3.11 on the worker, or use WorkerSetup conda")
        say("status", f"creating a virtual environment in {prefix}")
        venv.create(prefix, with_pip=True)
    else:
        conda = shutil.which("conda") or shutil.which("mamba") or shutil.which("micromamba")
        if conda is None:
            fail("--setup conda needs conda, mamba or micromamba on the worker's PATH")
        say("status", f"creating a conda environment in {prefix}")
        run([conda, "create", "--yes", "--quiet", "--prefix", str(prefix),
             f"python={PYTHON[0]}.{PYTHON[1]}", "pip"])
    say("progress", 20)
    python = str(env_python(prefix, setup))
    pip = [python, "-m", "pip", "install", "--disable-pip-version-check", "--no-input"]
    say("status", "installing the pinned requirements (Blender as bpy, numpy, scipy, ...)")
    run(pip + ["-r", str(requirements)])
    say("progress", 80)
    # --no-deps: every dependency is pinned in the requirements file, as in the project.
    say("status", f"installing {package}")
    run(pip + ["--no-deps", package])
    (prefix / COMPLETE).write_text(package + "\n")


def prepared(setup: str, requirements: Path, package: str, cache: Path) -> Path:
    """The bin folder of a complete environment for these inputs (built now if need be)."""
    if not requirements.is_file():
        fail(f"the requirements file {requirements} is not on this worker (WorkerRequirements)")
    prefix = cache / environment_key(setup, requirements.read_bytes(), package)
    with Lock(cache / f"{prefix.name}.lock"):
        if (prefix / COMPLETE).is_file():
            say("status", f"reusing the environment {prefix}")
        else:
            build(prefix, setup, requirements, package)
    return bin_folder(prefix, setup)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--setup", choices=SETUPS, required=True)
    parser.add_argument("--executable", required=True, help="the xsl-render command the tasks run")
    parser.add_argument("--requirements", help="pinned requirements file (pip, conda)")
    parser.add_argument("--package", help="pip requirement of the xsl-render package (pip, conda)")
    parser.add_argument("--cache", default="auto", help="folder for environments (auto: per user)")
    args = parser.parse_args(argv)
    # A cancelled setup (SIGTERM) ends through SystemExit, so the lock and files are closed.
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(143))
    path = os.environ.get("PATH", "")
    if args.setup != "none":
        if not args.requirements or not args.package:
            fail(f"--setup {args.setup} needs --requirements and --package")
        cache = default_cache() if args.cache in ("", "auto") else Path(args.cache).expanduser()
        folder = prepared(args.setup, Path(args.requirements), args.package, cache)
        path = str(folder) + os.pathsep + path
        say("env", f"PATH={path}")
    found = shutil.which(args.executable, path=path)
    if found is None:
        fail(f"'{args.executable}' is not on this worker's PATH ({path}); prepare the worker "
             "(docs/farm.md) or set WorkerSetup to pip or conda")
    say("status", f"xsl-render is {found}")
    say("progress", 100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
