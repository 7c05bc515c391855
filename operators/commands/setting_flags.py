"""How the command line names a setting in an error message: by its option (``--min-spp``).

Core and the add-on raise ``SettingError`` naming settings by their fields (``min_spp``,
``core.errors``); an option's argparse ``dest`` is the field it fills, and argparse derives
that dest from the option (``--min-spp`` -> ``min_spp``), so the option is the dest read
back. The option table names its own (``--guided-exponent`` sets ``exponent``);
:data:`FIELD_FLAGS` names the few other fields whose option is called otherwise.
``tests/test_setting_errors.py`` checks both against every option of every command.
"""
from __future__ import annotations

from ...core.errors import InputError, SettingError
from ...core.option_table import OPTIONS

#: Fields whose option is not their name read as a flag: field -> option.
FIELD_FLAGS = {
    "ceiling": "--max-spp",             # CurvesSettings, the contestants' and references' ceiling
    "seconds": "--equal-time",          # RenderRequest: uniform's equal time, adaptive's
    "longest_side": "--size",           # ValidationSettings
    "setup": "--worker-setup",          # WorkerSetup (farm)
    "package": "--worker-package",
    "python": "--worker-python",        # no option sets these two yet (their defaults hold);
    "cache": "--worker-cache",          # named as the worker's other options are
}


def flag(field: str) -> str:
    """The option that sets ``field``: the option table's (``core.option_table``), else
    :data:`FIELD_FLAGS`', else argparse's rule for a dest read backwards (``min_spp`` ->
    ``--min-spp``)."""
    option = OPTIONS.get(field)
    if option is not None and option.option:
        return option.option
    return FIELD_FLAGS.get(field) or "--" + field.replace("_", "-")


def in_flags(error: InputError) -> str:
    """``error``'s one line as the command line says it: each setting named by its option
    ("--min-spp 8 is larger than --max-spp 4")."""
    if isinstance(error, SettingError):
        return error.worded({field: flag(field) for field in error.values})
    return str(error)
