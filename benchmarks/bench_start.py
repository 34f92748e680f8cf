"""Process start of the package and the command line, against a baseline process in the same run.

Each figure is the median of N whole processes (``python -c ...`` or ``python -m shimmy ...``), the
baseline ``python -c "import numpy, scipy.linalg"`` measured interleaved with them, so that a busy
machine shifts both alike:

* ``import shimmy`` and ``python -m shimmy --help`` (target: within 0.2 s of the baseline);
* the Hopf scan at 150 kN as a command (target: within 0.35 s of the baseline).

    python benchmarks/bench_start.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

BASELINE = ("-c", "import numpy, scipy.linalg")
COMMANDS = {
    "import shimmy": ("-c", "import shimmy"),
    "python -m shimmy --help": ("-m", "shimmy", "--help"),
    "hopf --config nes --Fz 150000": ("-m", "shimmy", "hopf", "--config", "nes", "--Fz", "150000"),
}


def seconds(args: tuple[str, ...]) -> float:
    clock = time.perf_counter()
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True)
    elapsed = time.perf_counter() - clock
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(args)} failed:\n{done.stderr}")
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error(f"--repeats {args.repeats}: allowed at least 1")
    for command in COMMANDS.values():  # numba's on-disk cache filled, imports compiled
        seconds(command)
    base, times = [], {name: [] for name in COMMANDS}
    for _ in range(args.repeats):
        for name, command in COMMANDS.items():
            base.append(seconds(BASELINE))
            times[name].append(seconds(command))
    baseline = statistics.median(base)
    print(f"medians of {args.repeats} processes; baseline (import numpy, scipy.linalg) {baseline:.3f} s")
    for name, values in times.items():
        median = statistics.median(values)
        print(f"  {name:<34}{median:7.3f} s  ({median - baseline:+.3f} s against the baseline)")


if __name__ == "__main__":
    main()
