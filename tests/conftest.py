"""Shared fixtures. Tests that need Blender import bpy through ``blender``; the rest never do."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "example_blends"


@pytest.fixture(scope="session", autouse=True)
def reference_cache(tmp_path_factory):
    """Every test (and every command a test runs) keeps converged references in a folder of
    its own session, never in the user's cache (``core.validation.reference.cache_root``)."""
    folder = tmp_path_factory.mktemp("xsl_render_cache")
    saved = os.environ.get("XSL_RENDER_CACHE")
    os.environ["XSL_RENDER_CACHE"] = str(folder)
    yield folder
    if saved is None:
        os.environ.pop("XSL_RENDER_CACHE", None)
    else:
        os.environ["XSL_RENDER_CACHE"] = saved


def pytest_addoption(parser):
    parser.addoption("--slow", action="store_true",
                     help="also run the tests marked slow (the 50-seed X-map oracle suite)")


def pytest_collection_modifyitems(config, items):
    """Tests marked ``slow`` run only when asked for: ``--slow``, or a ``-m`` expression
    that names them (``-m slow``). A plain run, ``-m "not browser"`` included, leaves them out."""
    if config.getoption("--slow") or "slow" in (config.getoption("markexpr") or ""):
        return
    slow = [item for item in items if item.get_closest_marker("slow")]
    if slow:
        config.hook.pytest_deselected(items=slow)
        items[:] = [item for item in items if not item.get_closest_marker("slow")]


@pytest.fixture
def tolerance_units(request, monkeypatch):
    """Auto's tolerance as 0.05 / sqrt(spp) for the tests that are not rendered in Blender: their
    measures are about where a value falls between counts' tolerances, not about the calibrated
    constant (``NOISE_AT_ONE_SPP``), which its bench sets. Scenes rendered in Blender keep it."""
    from xsl_render.core.sampling import volume_estimator

    if request.node.get_closest_marker("blender") is None:
        monkeypatch.setattr(volume_estimator, "NOISE_AT_ONE_SPP", 0.05)


@pytest.fixture
def blender():
    """The bpy module with an empty factory-settings session (Cycles on the CPU)."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.engine = "CYCLES"
    bpy.context.scene.cycles.device = "CPU"
    return bpy


def xsl_render_cli(*args: str, timeout: float = 600, cwd: Path | None = None) -> subprocess.CompletedProcess:
    """Run the installed ``xsl-render`` console script, as a user would."""
    exe = Path(sys.executable).with_name("xsl-render" + (".exe" if os.name == "nt" else ""))
    return subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd or ROOT)


@pytest.fixture
def cli():
    return xsl_render_cli
