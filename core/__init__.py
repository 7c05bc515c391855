"""The Blender-independent engine of xsl_render: pure functions on numpy arrays.

Nothing in this package imports bpy. The Blender side (``addon``) turns a scene into the
plain data defined here (``scene_model``), these modules turn that data into director maps,
tile plans, composites and metrics, and ``addon`` renders with Cycles again.
"""
