"""The one error type for bad input from the user."""


class InputError(ValueError):
    """Bad input: a missing file, an impossible option, a scene we cannot use.

    The message is one line that names the problem; the command line prints it and exits
    with code 2, the Blender operators show it in a report. Never raised for our own bugs.
    """


class Cancelled(KeyboardInterrupt):
    """The user cancelled (a progress callback returned True, or Ctrl-C).

    A KeyboardInterrupt so that ``except Exception`` clean-up code never swallows it; the
    command line reports it as "cancelled" with exit code 130, like Ctrl-C.
    """
