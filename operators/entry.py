"""The ``xsl-render`` console script (``pyproject.toml``).

Its first instruction blocks SIGINT and SIGTERM, before any other thread exists, so that
Ctrl-C is answered by one watcher thread from start to end (``signals.py`` says why); a
Ctrl-C that came earlier still, while Python started, is answered here: nothing has been
done yet. Imported only by the console script: inside Blender (``x.batch()``) the process and
its signals are Blender's.
"""
try:
    import _signal

    if hasattr(_signal, "pthread_sigmask"):
        _signal.pthread_sigmask(_signal.SIG_BLOCK, (_signal.SIGINT, _signal.SIGTERM))
except KeyboardInterrupt:
    import os

    os.write(2, b"xsl-render: cancelled\n")
    os._exit(130)


def entry() -> None:
    import os
    import sys

    from ..core import temporaries
    from . import signals

    watcher = signals.start()
    temporaries.open_session()
    sys.meta_path.insert(0, _BlenderStartsUnderTheLock())
    from .cli import main

    try:
        code = main(watcher=watcher)
    finally:
        temporaries.seal()          # done: a Ctrl-C from here on changes nothing
        temporaries.close_session()
    # Blender prints its own report at interpreter exit (e.g. "Error: Not freed memory
    # blocks" after the denoiser's temporary images) straight to fd 1: after our last line,
    # which commands promise is theirs (demo prints the report's path last). Our output is
    # flushed; what Blender says from here on goes nowhere.
    sys.stdout.flush()
    sys.stderr.flush()
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    sys.exit(code)


class _BlenderStartsUnderTheLock:
    """Finds ``bpy`` as usual, but Blender starts (``import bpy``) under the temporaries' lock.

    Starting, Blender makes its session folder (``blender_*``) in ours, or in /tmp when ours
    is gone: a cancel removing ours meanwhile (the main thread runs whenever the watcher is in
    a system call) left the one or the other behind. So a cancel waits until Blender has
    started (it mostly waits for the GIL then anyway) and removes its folder with ours."""

    def find_spec(self, name, path=None, target=None):
        if name != "bpy":
            return None
        from importlib.machinery import PathFinder

        from ..core import temporaries

        spec = PathFinder.find_spec(name, path)
        if spec is not None and spec.loader is not None:
            create = spec.loader.create_module      # an extension module: Blender starts in it

            def create_module(module_spec):
                with temporaries.gate():
                    return create(module_spec)
            spec.loader.create_module = create_module
        return spec


if __name__ == "__main__":          # python -m xsl_render.operators.entry COMMAND ...
    entry()
