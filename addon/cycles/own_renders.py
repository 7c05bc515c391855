"""The renders the extension makes itself (tile windows, snapshots, the X-map oracle):
Auto Volumes (``addon.cycles.auto_volumes``) leaves them as they are set up."""
from __future__ import annotations

from contextlib import contextmanager

_depth = 0


@contextmanager
def own_render():
    """A block whose Blender renders are the extension's own."""
    global _depth
    _depth += 1
    try:
        yield
    finally:
        _depth -= 1


def rendering_own() -> bool:
    """Whether a render starting now is one of the extension's own."""
    return _depth > 0
