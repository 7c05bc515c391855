"""An example scene saved with some of its Cycles settings changed and nothing else, for the
benches that compare a setting against the file as it is (path guiding, the sample pattern)."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# In a fresh Python: opening a file in the bench's own process would replace its Blender data.
_SET_CYCLES = """
import bpy, json, sys
source, target, settings = sys.argv[sys.argv.index("--") + 1:]
bpy.ops.wm.open_mainfile(filepath=source)
for scene in bpy.data.scenes:
    for name, value in json.loads(settings).items():
        setattr(scene.cycles, name, value)
bpy.ops.wm.save_as_mainfile(filepath=target, copy=True)
"""


def cycles_copy(scene: str, folder: Path, **settings) -> Path:
    """``example_blends/<scene>.blend`` saved as ``folder/<scene>.blend`` with every scene's
    Cycles ``settings`` (name=value) set."""
    target = Path(folder) / f"{scene}.blend"
    subprocess.run([sys.executable, "-c", _SET_CYCLES, "--", str(ROOT / "example_blends" / f"{scene}.blend"),
                    str(target), json.dumps(settings)], check=True, capture_output=True)
    return target
