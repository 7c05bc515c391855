"""Subcommands of ``xsl-render``; each module has NAME, HELP, add_arguments() and run()."""
from . import experiment_analyse, experiment_serve, hotspots, info, saliency

COMMANDS = [info, saliency, experiment_serve, experiment_analyse, hotspots]
