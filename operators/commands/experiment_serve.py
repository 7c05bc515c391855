"""``xsl-render experiment-serve STIMULI_DIR``: run the paper's 2AFC experiment in a browser.

STIMULI_DIR holds ``<scene>.gold.png`` and ``<scene>.test.png`` per scene, shown pixel for pixel.
Each participant registers, is given a condition (alternating: no reference, reference) and
does one trial per scene in random order, the gold standard's place counterbalanced; every
answer is committed to SQLite (default STIMULI_DIR/experiment.sqlite) as it is given, with the
display time stamps the page measured. ``xsl-render experiment-analyse DB`` analyses it."""
from __future__ import annotations

from pathlib import Path

NAME = "experiment-serve"
HELP = ("serve the 2AFC experiment of section 6.2 (no reference / reference) on the "
        "<scene>.gold.png + <scene>.test.png pairs of a folder; answers go to SQLite")

#: Ctrl-C and SIGTERM stop the server cleanly (KeyboardInterrupt in its main thread).
INTERRUPTIBLE = True
#: The answers go to SQLite one by one as they come.
OUTPUTS_AS_A_SET = False

CONDITION_CHOICES = {
    "alternate": ("no-reference", "reference"),
    "no-reference": ("no-reference",),
    "reference": ("reference",),
}


def add_arguments(parser) -> None:
    from . import argtypes

    parser.add_argument("stimuli", metavar="STIMULI_DIR", type=argtypes.input_folder("stimuli folder"),
                        help="folder of <scene>.gold.png and <scene>.test.png pairs (same size per pair)")
    parser.add_argument("--port", type=argtypes.integer(0, 65535), default=8000,
                        help="TCP port (default 8000; 0 picks a free one)")
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to listen on (default 127.0.0.1, this machine only)")
    parser.add_argument("--db", metavar="FILE.sqlite", type=argtypes.output_file(),
                        help="answers database (default STIMULI_DIR/experiment.sqlite); "
                             "reuse it to continue an experiment")
    parser.add_argument("--condition", choices=sorted(CONDITION_CHOICES), default="alternate",
                        help="alternate: participants alternate between the two conditions "
                             "(the paper's first experiment); or one condition for everybody")


def database_path(args) -> Path:
    """--db, or by default STIMULI_DIR/experiment.sqlite."""
    return Path(args.db) if args.db else Path(args.stimuli) / "experiment.sqlite"


def files(args) -> tuple[dict, dict]:
    """The stimuli read (every PNG of the folder) and the answers database written (--db is
    an option's own)."""
    stimuli = {f"stimulus {path.name}": path for path in sorted(Path(args.stimuli).iterdir())
               if path.name.lower().endswith(".png")}
    return stimuli, ({} if args.db else {"the answers database": database_path(args)})


def check(args) -> None:
    from ...core.checks import writable_file

    if args.db is None:                     # the default: next to the stimuli
        writable_file(Path(args.stimuli) / "experiment.sqlite", name="the answers database")


def run(args) -> int:
    from ...core.psychophysics.stimuli import scan_stimuli
    from ..experiment_web.server import start_server

    pairs = scan_stimuli(args.stimuli)
    db_path = database_path(args)
    server = start_server(pairs, db_path, args.host, args.port, CONDITION_CHOICES[args.condition])
    # A terminal's Ctrl-C and a service manager's SIGTERM both end the session cleanly: the
    # command line's signal watcher raises KeyboardInterrupt here (INTERRUPTIBLE), from the
    # moment the address is printed, and the command line then ends with 130 or 143.
    try:
        server.say(f"{len(pairs)} scenes, condition {args.condition}; answers go to {db_path}")
        server.say(f"open {server.url} in the participant's browser (Ctrl-C stops)")
        server.serve_forever()
    except KeyboardInterrupt:
        server.say("stopped; every answer given is in the database")
    finally:
        server.server_close()
        server.store.close()
    return 0
