"""``python -m cmpsim``: the same command line as ``cmpsim`` (:mod:`cmpsim.cli`)."""

from .cli import main

if __name__ == "__main__":
    main(prog_name="cmpsim")
