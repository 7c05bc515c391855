"""Render the converged references shipped with the repository (example_blends/references/).

    .venv/bin/python tools/regenerate_reference.py [--scene road] [--spp N] [--resolution WxH]

The demo measures every run against the road scene's converged reference at its own settings
(512x288, max(1024, 16 x 64) = 1024 spp, seed 7); shipping it lets a fresh clone's demo skip a
render of about five minutes. Its cache key holds the .blend file's hash, the Blender version
and the denoiser's version (``addon.cycles.denoise.DENOISE_VERSION``), so changing road.blend,
Blender or the denoiser makes ``tests/test_reference.py`` fail until this script has been run
again and its output committed. Older entries of the same scene are removed.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FOLDER = ROOT / "example_blends" / "references"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", default="road", help="example scene (default road, the demo's)")
    parser.add_argument("--spp", type=int, help="samples per pixel (default the reference's default)")
    parser.add_argument("--resolution", help="WxH (default the scene's own)")
    args = parser.parse_args(argv)

    from xsl_render.addon.scene.blend_session import open_blend
    from xsl_render.addon.validation.reference import reference_inputs, render_reference
    from xsl_render.core.sampling.render_options import parse_resolution
    from xsl_render.core.validation.reference import write_reference

    blend = ROOT / "example_blends" / f"{args.scene}.blend"
    scene = open_blend(blend)
    inputs = reference_inputs(scene, blend, spp=args.spp,
                              resolution=parse_resolution(args.resolution) if args.resolution else None)
    print(f"{blend.name}: {inputs.resolution[0]}x{inputs.resolution[1]}, {inputs.spp} spp, seed "
          f"{inputs.seed}, Blender {inputs.blender}, denoiser {inputs.denoise}", flush=True)
    last = [0.0]

    def progress(fraction: float, message: str) -> bool:
        if time.monotonic() - last[0] > 15 or fraction >= 1.0:
            last[0] = time.monotonic()
            print(f"  {100 * fraction:5.1f}%  {message}", flush=True)
        return False

    image, stats = render_reference(scene, inputs, progress)
    entry = write_reference(FOLDER, inputs, image, stats, file_name=blend.name)
    for record in FOLDER.glob("*.json"):
        if record.stem == inputs.key:
            continue
        if json.loads(record.read_text(encoding="utf-8")).get("file") == blend.name:
            record.with_suffix(".exr").unlink(missing_ok=True)
            record.unlink()
            print(f"removed the older entry {record.stem}")
    size = entry.path.stat().st_size / 1e6
    print(f"wrote {entry.path.relative_to(ROOT)} ({size:.2f} MB) in {stats.seconds:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
