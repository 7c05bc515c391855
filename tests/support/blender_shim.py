"""A stand-in for the ``blender`` command, which bpy from PyPI does not have:
``blender_shim.py -b FILE --python SCRIPT -- ARGS`` loads FILE, runs SCRIPT as Blender runs
``--python`` (``sys.argv`` holding the whole command line) and exits with its code."""
from __future__ import annotations

import runpy
import sys


def main(argv: list[str]) -> int:
    if argv[:1] != ["-b"] or "--python" not in argv:
        print(f"blender_shim: only '-b FILE --python SCRIPT [-- ARGS]' (got {argv})", file=sys.stderr)
        return 2
    blend, script = argv[1], argv[argv.index("--python") + 1]
    import bpy

    bpy.ops.wm.open_mainfile(filepath=blend, load_ui=False)
    sys.argv = ["blender", *argv]
    try:
        runpy.run_path(script, run_name="__main__")
    except SystemExit as exit:
        return int(exit.code or 0)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
