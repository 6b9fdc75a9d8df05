"""``python -m cmpsim.cli``: the same as the ``cmpsim`` command."""

from . import main

if __name__ == "__main__":  # pragma: no cover
    main()
