"""Ctrl-C on the command line becomes a cancel request, even while C code runs."""
from __future__ import annotations

import os
import signal
import time

from xsl_render.operators.interrupt import InterruptToCancel


def test_ctrl_c_requests_a_cancel_and_restores_the_handler(capsys):
    before = signal.getsignal(signal.SIGINT)
    with InterruptToCancel() as interrupt:
        progress = interrupt.wrap(lambda fraction, message: False)
        assert progress(0.1, "tile 1/9") is False
        os.kill(os.getpid(), signal.SIGINT)
        deadline = time.monotonic() + 5.0
        while not interrupt.requested and time.monotonic() < deadline:
            time.sleep(0.01)
        assert interrupt.requested
        assert progress(0.2, "tile 2/9") is True
    assert signal.getsignal(signal.SIGINT) is before
    assert "cancelling after the current render" in capsys.readouterr().err
