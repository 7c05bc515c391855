"""The extension as Blender's own tooling sees it: validate, build, install into a stock bpy.

The install runs in a separate Python that sees only what a stock Blender bundles (bpy,
numpy, OpenImageIO, requests, zstandard, ...), so scikit-image and the other runtime
dependencies must come from the wheels the zip ships.
"""
from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import tomllib
from pathlib import Path

import pytest

from conftest import ROOT

pytestmark = pytest.mark.blender

# What Blender's own Python carries; everything else the extension needs must be a wheel.
STOCK_BLENDER_PACKAGES = ("bpy", "numpy", "numpy.libs", "OpenImageIO", "zstandard", "requests",
                          "certifi", "charset_normalizer", "idna", "urllib3", "Cython", "cython.py")

INSTALL_SCRIPT = r"""
import sys
import bpy
zip_path = sys.argv[-1]
result = bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                                  enable_on_install=True)
assert result == {"FINISHED"}, result
assert "bl_ext.user_default.xsl_render" in bpy.context.preferences.addons.keys()
assert hasattr(bpy.ops.xsl, "scene_info")
import skimage.filters, skimage.transform, scipy.ndimage, flip_evaluator
for module in (skimage, scipy, flip_evaluator):
    assert "/extensions/" in module.__file__.replace("\\", "/"), module.__file__
print("INSTALLED-AND-REGISTERED")
"""


def test_manifest_is_complete():
    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    assert manifest["schema_version"] == "1.0.0" and manifest["id"] == "xsl_render"
    assert manifest["blender_version_min"] == "4.2.0"
    assert manifest["license"] == ["SPDX:GPL-3.0-or-later"]
    assert manifest["permissions"]["files"]
    excluded = manifest["build"]["paths_exclude_pattern"]
    for pattern in ("/tests/", "/example_blends/", "/.venv/", "__pycache__/"):
        assert pattern in excluded


@pytest.fixture(scope="module")
def built_zips(tmp_path_factory):
    out = tmp_path_factory.mktemp("dist")
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "build_extension.py"), "--out", str(out)],
                            capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stdout + result.stderr
    return {p.name: p for p in out.glob("*.zip")}


def test_validates_and_builds_one_zip_per_platform(built_zips):
    assert sorted(built_zips) == ["xsl_render-0.1.0-linux_x64.zip", "xsl_render-0.1.0-macos_arm64.zip",
                                  "xsl_render-0.1.0-windows_x64.zip"]


def test_zip_holds_the_extension_and_not_the_repository(built_zips):
    import zipfile

    names = zipfile.ZipFile(built_zips["xsl_render-0.1.0-linux_x64.zip"]).namelist()
    assert "blender_manifest.toml" in names and "__init__.py" in names and "core/camera.py" in names
    assert not [n for n in names if n.startswith(("tests/", "example_blends/", ".venv/", "bench/"))]
    wheels = [n for n in names if n.startswith("wheels/")]
    assert wheels and all("win_amd64" not in n and "macosx" not in n for n in wheels)


def test_linux_zip_installs_into_a_stock_bpy_and_registers(built_zips, tmp_path):
    site = Path(sysconfig.get_paths()["purelib"])
    stock = tmp_path / "stock"
    stock.mkdir()
    for name in STOCK_BLENDER_PACKAGES:
        if (site / name).exists():
            (stock / name).symlink_to(site / name)
    script = tmp_path / "install.py"
    script.write_text(INSTALL_SCRIPT)
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(tmp_path),
           "PYTHONPATH": str(stock), "BLENDER_USER_RESOURCES": str(tmp_path / "user")}
    result = subprocess.run([sys.executable, "-S", "-s", str(script),
                             str(built_zips["xsl_render-0.1.0-linux_x64.zip"])],
                            capture_output=True, text=True, env=env, timeout=600)
    assert "INSTALLED-AND-REGISTERED" in result.stdout, result.stdout[-3000:] + result.stderr[-3000:]
