"""Subcommands of ``xsl-render``; each module has NAME, HELP, add_arguments() and run()."""
from . import info, saliency

COMMANDS = [info, saliency]
