"""Run ``cmpsim`` with a sweep of which only the first K points to start may finish.

``python tests/sweep_gate.py K TOKEN_DIR ARGS...`` runs the command line ``cmpsim ARGS...``
with the per-point solver replaced by :func:`gated_run_point`: each point that starts tries
to take one of K tokens (files created with O_EXCL in TOKEN_DIR, so processes cannot take the
same one); a point with a token is solved as usual, every other point blocks forever. Exactly
K points finish whichever points the scheduler starts first, so a signalled run cannot end
before the signal and the number of saved points is known: the kill and Ctrl-C tests have no
race left, whatever the load of the machine.

The gate is a module of its own so that Dask pickles it by reference: the worker processes
import this file (the parent's ``sys.path`` reaches them) and run the same gate.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from pathlib import Path

TOKENS = "CMPSIM_TEST_FINISHING_POINTS"
TOKEN_DIR = "CMPSIM_TEST_TOKEN_DIR"


def _take_token() -> bool:
    folder = Path(os.environ[TOKEN_DIR])
    for k in range(int(os.environ[TOKENS])):
        try:
            os.close(os.open(folder / f"token-{k}", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
            return True
        except FileExistsError:
            continue
    return False


def gated_run_point(task, prev=None, prev2=None):
    """The sweep's point function if this point gets a token; otherwise block forever."""
    from cmpsim import sweeps

    if not _take_token():
        threading.Event().wait()  # never set: the point never finishes
    real = getattr(sweeps, "_REAL_RUN_POINT", sweeps._run_point)  # unpatched in a Dask worker
    return real(task, prev, prev2)


def main(argv: list[str]) -> None:
    from cmpsim import cli, sweeps

    # What a terminal gives its foreground job: SIGINT at its default, so Ctrl-C raises
    # KeyboardInterrupt. A test suite started in the background (`cmd &` in a script, nohup,
    # some CI runners) hands SIGINT down as ignored, and a Python process that starts with it
    # ignored never raises KeyboardInterrupt: the Ctrl-C test then waited for a run that,
    # like any Unix program started that way, correctly ignored the signal (the hang of the
    # newcomer runs, whose quick start was started in the background).
    signal.signal(signal.SIGINT, signal.default_int_handler)

    os.environ[TOKENS], os.environ[TOKEN_DIR] = argv[0], str(Path(argv[1]).resolve())
    Path(argv[1]).mkdir(parents=True, exist_ok=True)
    sweeps._REAL_RUN_POINT = sweeps._run_point
    import sweep_gate  # by its module name, so that pickling refers to an importable module

    sweeps._run_point = sweep_gate.gated_run_point
    sys.argv = ["cmpsim", *argv[2:]]
    cli.main()


if __name__ == "__main__":
    main(sys.argv[1:])
