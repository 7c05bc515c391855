"""The one error type for bad input from the user."""


class InputError(ValueError):
    """Bad input: a missing file, an impossible option, a scene we cannot use.

    The message is one line that names the problem; the command line prints it and exits
    with code 2, the Blender operators show it in a report. Never raised for our own bugs.
    """
