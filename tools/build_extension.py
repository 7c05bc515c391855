"""Download the pinned wheels and build the Blender extension zips (``python3 run.py build``).

    python tools/build_extension.py [--out DIR] [--sync-manifest] [--skip-download]

The lines tagged ``# wheel`` in requirements.lock are downloaded as binary wheels for every
platform of the manifest (never compiled); the manifest's ``wheels`` list must name exactly
them (``--sync-manifest`` rewrites it) and its Blender range hold only releases whose Python the
wheels are built for; then Blender's own ``blender_ext.py`` validates the repository and builds
one zip per platform into DIR (``dist/``). Run it with the project's ``.venv`` Python, which
holds Blender's extension tool."""
from __future__ import annotations

import argparse
import importlib.util
import re
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
WHEEL_DIR = ROOT / "wheels"

# Blender platform -> pip --platform tags, newest first. A wheel that names any of these
# runs on Blender's minimum OS for that platform (glibc 2.28, Windows 10, macOS 11).
PIP_PLATFORMS = {
    "linux-x64": ["manylinux_2_28_x86_64", "manylinux_2_27_x86_64", "manylinux_2_24_x86_64",
                  "manylinux_2_17_x86_64", "manylinux2014_x86_64"],
    "windows-x64": ["win_amd64"],
    "macos-arm64": ["macosx_12_0_arm64", "macosx_11_0_arm64"],
}


#: The Python each Blender release series ships (Blender's release notes, "Python" section);
#: a binary cp311 wheel loads only in the 3.11 ones. 5.1 moves on to Python 3.13.
BLENDER_PYTHON = {(4, 2): "311", (4, 3): "311", (4, 4): "311", (4, 5): "311", (5, 0): "311",
                  (5, 1): "313"}


def _release(version: str) -> tuple[int, int]:
    major, minor = version.split(".")[:2]
    return int(major), int(minor)


def check_blender_range(manifest: dict, wheels: list[str]) -> None:
    """SystemExit unless every Blender from the manifest's minimum up to (not including) its
    maximum ships the Python the binary wheels (``-cpXYZ-``) are built for."""
    tags = {match.group(1) for name in wheels for match in [re.search(r"-cp(\d+)-", name)] if match}
    if not tags:
        return                          # pure-Python wheels load in any Blender
    if "blender_version_max" not in manifest:
        raise SystemExit(f"build_extension: the wheels are built for cp{'/'.join(sorted(tags))} only; "
                         "the manifest needs a blender_version_max")
    low, high = _release(manifest["blender_version_min"]), _release(manifest["blender_version_max"])
    newest = max(BLENDER_PYTHON)
    if high > (newest[0], newest[1] + 1):
        raise SystemExit(f"build_extension: Blender {manifest['blender_version_max']} is past the "
                         "releases whose Python this tool knows (BLENDER_PYTHON)")
    covered = [release for release in BLENDER_PYTHON if low <= release < high]
    wrong = [f"{a}.{b}" for a, b in covered if BLENDER_PYTHON[(a, b)] not in tags]
    if wrong:
        raise SystemExit(f"build_extension: Blender {', '.join(wrong)} ship(s) a Python the wheels "
                         f"(cp{'/'.join(sorted(tags))}) are not built for; lower blender_version_max")


def pinned_wheels(lock: Path = ROOT / "requirements.lock") -> list[str]:
    """The ``name==version`` requirements tagged ``# wheel`` in the lock file."""
    specs = []
    for line in lock.read_text().splitlines():
        requirement, _, comment = line.partition("#")
        if requirement.strip() and comment.strip() == "wheel":
            specs.append(requirement.strip())
    return specs


def manifest_wheels(manifest: Path = ROOT / "blender_manifest.toml") -> list[str]:
    return tomllib.loads(manifest.read_text()).get("wheels", [])


def download(specs: list[str], platforms: list[str]) -> list[str]:
    """pip-download every spec for every platform; returns the manifest paths of the files."""
    WHEEL_DIR.mkdir(exist_ok=True)
    names: set[str] = set()
    for platform in platforms:
        tags = [arg for tag in PIP_PLATFORMS[platform] for arg in ("--platform", tag)]
        subprocess.check_call([
            sys.executable, "-m", "pip", "download", "-q", "--disable-pip-version-check",
            "--only-binary=:all:", "--no-deps", "--python-version", "3.11",
            "--implementation", "cp", "--abi", "cp311", *tags, "-d", str(WHEEL_DIR), *specs,
        ])
        names.update(wheel_files_for(specs, platform))
    return sorted(f"./wheels/{name}" for name in names)


def wheel_files_for(specs: list[str], platform: str) -> list[str]:
    """The files in wheels/ that satisfy ``specs`` on ``platform`` (one per spec)."""
    tags = PIP_PLATFORMS[platform]
    found = []
    for spec in specs:
        name, version = spec.split("==")
        stem = re.sub(r"[-_.]+", "_", name).lower()
        candidates = [p.name for p in WHEEL_DIR.glob("*.whl")
                      if p.name.lower().startswith(f"{stem}-{version}-")]
        usable = [c for c in candidates if c.endswith("-none-any.whl")
                  or any(tag in c for tag in tags)]
        if not usable:
            raise SystemExit(f"build_extension: no {platform} wheel for {spec} in wheels/")
        found.append(sorted(usable)[0])
    return found


def write_manifest_wheels(paths: list[str], manifest: Path = ROOT / "blender_manifest.toml") -> None:
    text = manifest.read_text()
    block = "wheels = [\n" + "".join(f'  "{p}",\n' for p in paths) + "]"
    new, count = re.subn(r"wheels = \[[^\]]*\]", block, text)
    if count != 1:
        raise SystemExit("build_extension: no single `wheels = [...]` list in the manifest")
    manifest.write_text(new)


def blender_ext() -> Path:
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        raise SystemExit("build_extension: the bpy module is not installed; run with .venv's Python")
    found = sorted(Path(spec.submodule_search_locations[0]).glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not found:
        raise SystemExit("build_extension: blender_ext.py not found inside the bpy module")
    return found[-1]


def build(out: Path) -> list[Path]:
    tool = blender_ext()
    subprocess.check_call([sys.executable, str(tool), "validate", str(ROOT)])
    out.mkdir(parents=True, exist_ok=True)
    subprocess.check_call([sys.executable, str(tool), "build", "--source-dir", str(ROOT),
                           "--output-dir", str(out), "--split-platforms"])
    return sorted(out.glob("xsl_render-*.zip"))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "dist", help="folder for the zips (dist/)")
    parser.add_argument("--sync-manifest", action="store_true",
                        help="rewrite the manifest's wheels list from requirements.lock")
    parser.add_argument("--skip-download", action="store_true", help="use the files already in wheels/")
    args = parser.parse_args(argv)

    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    platforms = manifest["platforms"]
    specs = pinned_wheels()
    if args.skip_download:
        paths = sorted({f"./wheels/{n}" for p in platforms for n in wheel_files_for(specs, p)})
    else:
        paths = download(specs, platforms)
    if args.sync_manifest:
        write_manifest_wheels(paths)
    elif paths != sorted(manifest_wheels()):
        missing = sorted(set(paths) - set(manifest_wheels()))
        extra = sorted(set(manifest_wheels()) - set(paths))
        raise SystemExit("build_extension: the manifest's wheels differ from requirements.lock "
                         f"(not listed: {missing}; listed but not pinned: {extra}); "
                         "run with --sync-manifest")
    check_blender_range(manifest, paths)
    for zip_path in build(args.out):
        print(zip_path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
