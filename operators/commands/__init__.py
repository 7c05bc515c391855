"""Subcommands of ``xsl-render``; each module has NAME, HELP, add_arguments() and run().
``GROUPS`` is how ``xsl-render --help`` lists them: what a user runs first, the paper's
system and the measurements apart, then what job templates run."""
from . import (compare, curves, demo, experiment, experiment_analyse, experiment_serve, farm,
               farm_task, hotspots, info, maps, reference, render, saliency, xmap)

GROUPS = {
    "commands": [render, info, farm, compare, demo],
    "research (the paper's system, Sundstedt et al. 2007, and the measurements)":
        [maps, xmap, saliency, reference, curves, experiment, experiment_serve, experiment_analyse,
         hotspots],
    "run by farm jobs": [farm_task],
}
COMMANDS = [command for group in GROUPS.values() for command in group]
