"""Subcommands of ``xsl-render``; each module has NAME, HELP, add_arguments() and run()."""
from . import (compare, demo, experiment, experiment_analyse, experiment_serve, farm, farm_task,
               hotspots, info, maps, render, saliency, xmap)

COMMANDS = [info, maps, xmap, saliency, render, compare, experiment, demo, farm, farm_task,
            experiment_serve, experiment_analyse, hotspots]
