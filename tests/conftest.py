"""Shared fixtures. Tests that need Blender import bpy through ``blender``; the rest never do."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "example_blends"


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
