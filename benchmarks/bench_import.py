"""Import time of `import cmpsim` (lazy API) against a bare interpreter and `import numpy`.

Run: python benchmarks/bench_import.py [--repeat 15]
Reports the median wall time of fresh interpreters, and the ratio to the bare start-up.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time


def median_time(code: str, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True)
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=15)
    n = ap.parse_args().repeat
    bare = median_time("pass", n)
    numpy = median_time("import numpy", n)
    cm = median_time("import cmpsim", n)
    solve_ready = median_time("import cmpsim; cmpsim.solve", n)
    print(f"bare interpreter       {bare * 1e3:7.1f} ms")
    print(f"import numpy           {numpy * 1e3:7.1f} ms  ({numpy / bare:.2f} x bare)")
    print(f"import cmpsim          {cm * 1e3:7.1f} ms  ({cm / bare:.2f} x bare; {(cm - bare) * 1e3:.1f} ms own)")
    print(f"import + cmpsim.solve  {solve_ready * 1e3:7.1f} ms  (loads numpy/scipy on first use)")


if __name__ == "__main__":
    main()
