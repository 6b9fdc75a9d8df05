"""What a user pays before cmpsim computes: import times, and `cmpsim run` against the bare
scientific import it cannot avoid.

Run: python benchmarks/bench_import.py [--repeat 15]

* ``import cmpsim`` (the lazy API) against a bare interpreter and ``import numpy``;
* ``cmpsim run`` (the base case, whole process: interpreter, imports, solve, table) against
  ``python -c "import numpy, scipy.sparse.linalg"``, the libraries the solver needs. The two
  commands run in turn (paired runs, so that a change of the machine's load hits both), and the
  ratio reported is the median of the per-pair ratios, with the medians of each command.
  Issue 31 measured 3.07x on 26d31a1 and asks for at most 1.8x.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import time


def wall(cmd: list[str]) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def median_time(code: str, repeat: int) -> float:
    return statistics.median(wall([sys.executable, "-c", code]) for _ in range(repeat))


def paired(a: list[str], b: list[str], repeat: int) -> tuple[float, float, float]:
    """Median wall of a, of b, and the median of the per-pair ratios a/b (a and b alternate)."""
    wall(a), wall(b)  # warm the file cache
    ta, tb = [], []
    for _ in range(repeat):
        ta.append(wall(a))
        tb.append(wall(b))
    return statistics.median(ta), statistics.median(tb), statistics.median(x / y for x, y in zip(ta, tb))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=15)
    n = ap.parse_args().repeat
    import os

    cached = "no: PYTHONDONTWRITEBYTECODE is set, cmpsim's modules are compiled at every start" if os.environ.get("PYTHONDONTWRITEBYTECODE") else "yes (unless the source tree is read-only)"
    print(f"cmpsim bytecode cached: {cached}")
    bare = median_time("pass", n)
    numpy = median_time("import numpy", n)
    cm = median_time("import cmpsim", n)
    print(f"bare interpreter       {bare * 1e3:7.1f} ms")
    print(f"import numpy           {numpy * 1e3:7.1f} ms  ({numpy / bare:.2f} x bare)")
    print(f"import cmpsim          {cm * 1e3:7.1f} ms  ({cm / bare:.2f} x bare; {(cm - bare) * 1e3:.1f} ms own)")
    exe = shutil.which("cmpsim") or sys.exit("the cmpsim command is not on PATH: pip install -e .")
    run, sci, ratio = paired([exe, "run"], [sys.executable, "-c", "import numpy, scipy.sparse.linalg"], n)
    print(f"cmpsim run             {run * 1e3:7.1f} ms  (median wall)")
    print(f"numpy + sparse.linalg  {sci * 1e3:7.1f} ms  (median wall)")
    print(f"cmpsim run / bare scientific import: {ratio:.2f} x (median of {n} paired ratios; issue 31: <= 1.8)")


if __name__ == "__main__":
    main()
