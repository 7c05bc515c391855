"""The Blender-independent engine of xsl_render: pure functions on numpy arrays; nothing here
imports bpy.

``addon`` turns a scene into the plain data of ``media``; ``maps`` makes director maps of it,
``sampling`` plans and composites renders and chooses auto's estimator, ``validation``
measures renders against references and writes the report, ``psychophysics`` runs the 2AFC
experiment, ``farm`` writes farm jobs, ``panel`` holds the panel's options. The modules at
this level are the helpers they share (errors, checks, files, imageio, tonemap, camera,
frames, progress) and the option table every front end is built from (``option_table``)."""
