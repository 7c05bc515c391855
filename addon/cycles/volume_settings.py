"""Whether this Blender's Cycles has the volume settings auto's choice writes (Blender 5:
ray marching per scene, a step per material and per world). The panel greys Auto Volumes out
with the reason, and the render handlers keep the file's settings, where it has not."""
from __future__ import annotations

#: (owner, Cycles setting) auto's choice needs.
NEEDED_SETTINGS = (("scene", "volume_biased"), ("scene", "volume_step_rate"),
                   ("material", "volume_step_rate"), ("world", "volume_step_size"))


def unsupported() -> str:
    """Why this Blender cannot render with auto's choice ("" where it can)."""
    import bpy

    owners = {"scene": bpy.types.Scene, "material": bpy.types.Material, "world": bpy.types.World}
    for owner, name in NEEDED_SETTINGS:
        cycles = owners[owner].bl_rna.properties.get("cycles")
        if cycles is None:
            return "Cycles is not enabled"
        if name not in cycles.fixed_type.properties:
            return f"this Blender's Cycles has no {owner} setting '{name}' (it needs Blender 5.0 or newer)"
    return ""
