"""Run ``cmpsim lot`` stopped for good once wafer K's checkpoint is written.

``python tests/lot_gate.py K ARGS...`` runs the command line ``cmpsim ARGS...`` with the lot's
checkpoint writer wrapped: it writes as usual, and once it has written a checkpoint whose
``next_wafer`` is K or more, the lot blocks forever. A test that waits for that checkpoint and then
sends SIGKILL kills the lot mid-lot, after exactly K wafers, whatever the load of the machine:
no race (the same idea as tests/sweep_gate.py).
"""

from __future__ import annotations

import sys
import time


def main() -> None:
    stop_at = int(sys.argv[1])
    from cmpsim.polisher import lot

    write = lot.write_checkpoint

    def gated(path, checkpoint):
        write(path, checkpoint)
        if checkpoint.next_wafer >= stop_at:
            while True:  # the test's SIGKILL ends it
                time.sleep(3600)

    lot.write_checkpoint = gated
    from cmpsim.cli import main as cli

    cli(sys.argv[2:])


if __name__ == "__main__":
    main()
