"""Subcommands of ``xsl-render``; each module has NAME, HELP, add_arguments() and run()."""
from . import info, render

COMMANDS = [info, render]
