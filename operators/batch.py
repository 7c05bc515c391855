"""The batch entry: ``xsl-render`` commands inside ``blender -b scene.blend``.

    blender -b scene.blend --python-expr "import bl_ext.user_default.xsl_render as x; x.batch()" \
        -- render --mode xsl --max-spp 16 --out out.exr

Everything after ``--`` is parsed and run by the ``xsl-render`` command's own code, on the file
Blender has open (SCENE.blend left out; nothing is written to it). A failure raises
``SystemExit`` with the command's code (2, 1, 130) after its one-line message; Ctrl-C is
answered from the entry's first instruction (``operators/interrupt.py``)."""
from __future__ import annotations

import sys


def arguments_after_separator(argv: list[str]) -> list[str]:
    """What follows the first ``--`` (Blender ignores the rest of its command line there)."""
    return list(argv[argv.index("--") + 1:]) if "--" in argv else []


def batch(argv: list[str] | None = None, early_signals: list | tuple = ()) -> int:
    """Run one ``xsl-render`` command on the open file; ``argv`` defaults to what follows
    ``--`` on Blender's command line. ``early_signals``: the Ctrl-Cs noted since the entry's
    first instruction (``xsl_render.batch``); more may come until the watcher is in place."""
    from .cli import main
    from .interrupt import InterruptToCancel

    args = arguments_after_separator(sys.argv) if argv is None else list(argv)
    with InterruptToCancel(before_work=True) as interrupt:
        if early_signals:
            interrupt.requested = True      # (``main`` says so once it would begin the work)
        code = main(args, in_blender=True, begin_work=interrupt.begin_work)
    if code:
        raise SystemExit(code)
    return 0
