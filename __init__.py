"""XSL Render: perceptual selective rendering of participating media with Cycles.

Implements Sundstedt, Gutierrez, Anson, Banterle and Chalmers, "Perceptual Rendering of
Participating Media" (ACM TAP 4(3), 2007). This file only registers the add-on and offers
the batch entry; the bpy-free engine is in ``core``, the Blender side in ``addon`` and
``operators``.
"""


def register():
    # Imported here so that ``core`` and the command line can be used without bpy.
    from . import addon, operators

    addon.register()
    operators.register()


def unregister():
    from . import addon, operators

    operators.unregister()
    addon.unregister()


def batch(argv=None) -> int:
    """``xsl-render`` commands on the file ``blender -b`` has open (``operators/batch.py``):

        blender -b scene.blend --python-expr "import bl_ext.user_default.xsl_render as x; x.batch()" \\
            -- render --mode xsl --max-spp 16 --out out.exr

    Its first instruction notes Ctrl-C instead of raising KeyboardInterrupt (inside an
    import it would leave modules half made and print a traceback); the batch entry answers
    a Ctrl-C noted before its work begins with 130 and one line.
    """
    signals = []
    try:
        import _signal

        previous = _signal.signal(_signal.SIGINT, lambda signum, frame: signals.append(signum))
    except KeyboardInterrupt:
        raise SystemExit(_cancelled()) from None
    except ValueError:                  # not the main thread: the signals are not ours to take
        _signal = None
    try:
        from .operators.batch import batch as run

        return run(argv, early_signals=signals)
    finally:
        if _signal is not None:
            # (None: a handler not set from Python, which cannot be put back: Python's own.)
            _signal.signal(_signal.SIGINT, previous if previous is not None else _signal.default_int_handler)


def _cancelled() -> int:
    import sys

    print("xsl-render: cancelled", file=sys.stderr)
    return 130


def render_chunk(argv=None) -> int:
    """A farm task of a plain Blender job (``core/farm/blender_job.py``), inside the worker's
    Blender: ``blender -b scene.blend --python xsl_render_chunk.py -- --scene-name S --frames
    1-8 --output DIR`` renders the frames as Blender does, with Auto Volumes."""
    import sys

    from .addon.farm.blender_chunk import render_chunk as run

    return run(sys.argv[sys.argv.index("--") + 1:] if argv is None else argv)
