"""Subcommands of ``xsl-render``; each module has NAME, HELP, add_arguments() and run()."""
from . import compare, experiment_analyse, experiment_serve, hotspots, info, maps, saliency, xmap

COMMANDS = [info, maps, xmap, saliency, compare, experiment_serve, experiment_analyse, hotspots]
