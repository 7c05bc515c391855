"""The one error type for bad input from the user, and its form that names settings."""
from __future__ import annotations

import functools
from collections.abc import Mapping


class InputError(ValueError):
    """Bad input: a missing file, an impossible option, a scene we cannot use.

    The message is one line that names the problem; the command line prints it and exits
    with code 2, the Blender operators show it in a report. Never raised for our own bugs.
    """


class _Named:
    """One setting in a message: ``{field}`` is its name and value together (as the front
    end pairs them), ``{field.name}`` its name alone, ``{field.value}`` its value alone. A
    format spec applies to the value (``{time_budget.value:g}``, ``{min_spp:d}``)."""

    def __init__(self, name: str, value: object, pair: str):
        self.name, self.value, self._pair = name, value, pair

    def __format__(self, spec: str) -> str:
        return self._pair.format(name=self.name, value=format(self.value, spec))


class SettingError(InputError):
    """Bad input that names settings: each by its field (the attribute of the options'
    dataclass that holds it, ``min_spp``), so that each front end can call it by its own
    name (the command line by its flag, ``--min-spp``; the panel by its label, "Min Samples").

    ``str()`` names the fields as they are ("min_spp 8 is larger than max_spp 4"); a front
    end calls :meth:`worded` with its own names.

    Parameters
    ----------
    template
        The one-line message, a :meth:`str.format` template with a placeholder per setting:
        ``{min_spp}`` for its name and value ("min_spp 8"), ``{min_spp.name}`` for its name,
        ``{min_spp.value}`` for its value. Other text holds no braces (:func:`verbatim`
        doubles those of text the user typed).
    **values
        Each setting's value as the message shows it (a number, or text such as "0.5 s").

    Examples
    --------
    >>> error = SettingError("{min_spp} is larger than {max_spp}", min_spp=8, max_spp=4)
    >>> str(error)
    'min_spp 8 is larger than max_spp 4'
    >>> error.worded({"min_spp": "Min Samples", "max_spp": "Max Samples"}, pair="{name} ({value})")
    'Min Samples (8) is larger than Max Samples (4)'
    """

    def __init__(self, template: str, /, **values: object):
        self.template = template
        self.values = values
        super().__init__(self.worded({}))

    def worded(self, names: Mapping[str, str], pair: str = "{name} {value}") -> str:
        """The message with each setting called as ``names`` calls it (a field missing from
        ``names`` keeps its field name); ``pair`` joins a name and its value for ``{field}``."""
        return self.template.format_map({field: _Named(names.get(field, field), value, pair)
                                         for field, value in self.values.items()})

    def __reduce__(self):
        # The message is built from the template: rebuild from it, not from the message.
        return functools.partial(type(self), self.template, **self.values), ()


def verbatim(text: object) -> str:
    """``text`` (a path, a name the user typed) as literal text of a :class:`SettingError`
    template: its braces doubled, so that ``format`` shows them as they are."""
    return str(text).replace("{", "{{").replace("}", "}}")


def setting_refused(field: str, value: object, text: str) -> SettingError:
    """The error "{field} ``text``" for a setting refused by a general check
    (``core.checks``): the setting named first, ``text`` (plain words) after it."""
    return SettingError(f"{{{field}.name}} {verbatim(text)}", **{field: value})


class Field(str):
    """A setting's field name given where a check (``core.checks``) takes the name of what
    it checks: the check then raises a :class:`SettingError` naming that setting."""


class Cancelled(KeyboardInterrupt):
    """The user cancelled (a progress callback returned True, or Ctrl-C).

    A KeyboardInterrupt so that ``except Exception`` clean-up code never swallows it; the
    command line reports it as "cancelled" with exit code 130, like Ctrl-C.
    """
