"""Subcommands of ``xsl-render``; each module has NAME, HELP, add_arguments() and run()."""
from . import (compare, curves, demo, experiment, experiment_analyse, experiment_serve, farm,
               farm_task, hotspots, info, maps, reference, render, saliency, xmap)

COMMANDS = [info, maps, xmap, saliency, render, compare, reference, curves, experiment, demo, farm,
            farm_task, experiment_serve, experiment_analyse, hotspots]
