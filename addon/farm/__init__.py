"""The farm's Blender side: the tasks of a job bundle (``tasks.py``), which ``xsl-render
farm-task`` runs on a worker."""
