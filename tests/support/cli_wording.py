"""Core errors as the command line words them: a setting named by its option (``--max-spp``),
as ``operators/commands/setting_flags.py`` names it when ``xsl-render`` prints the error."""
from __future__ import annotations

import re
from contextlib import contextmanager

import pytest

from xsl_render.core.errors import InputError
from xsl_render.operators.commands.setting_flags import in_flags


@contextmanager
def refused_in_flags(pattern: str, kind: type[BaseException] = InputError):
    """``pytest.raises(kind, match=pattern)``, with ``pattern`` searched in the message as
    the command line prints it rather than in core's own wording (which names fields)."""
    with pytest.raises(kind) as refused:
        yield refused
    message = in_flags(refused.value) if isinstance(refused.value, InputError) else str(refused.value)
    assert re.search(pattern, message), message
