"""Process start of the package and the command line, against a baseline process in the same run.

Each figure is the median of N whole processes (``python -c ...`` or ``python -m shimmy ...``), the
baseline ``python -c "import numpy, scipy.linalg"`` measured interleaved with them, so that a busy
machine shifts both alike:

* ``import shimmy`` and ``python -m shimmy --help`` (target: within 0.2 s of the baseline);
* the Hopf scan at 150 kN as a command, computed (``--no-cache``; target: within 0.35 s of the
  baseline);
* a one-parameter diagram at 150 kN as a command, computed (target: <= 1.2 s), and the fold and
  torus curves of ``original`` as a command (target: <= 6 s), each against its own work in a warm
  process (the same call timed in this process, kernels loaded), the difference being start-up;
* a repeated ``map`` (``original``, the default plane and grid) answered from the shared result cache,
  as text and as JSON (target: within 0.4 s of the baseline); the first run, which computes the map
  and stores it, is timed once and printed for comparison.

The commands run on a fresh cache directory of their own (``SHIMMY_CACHE_DIR``).

    python benchmarks/bench_start.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

BASELINE = ("-c", "import numpy, scipy.linalg")
MAP = ("-m", "shimmy", "map", "--config", "original", "--progress", "none")
COMMANDS = {
    "import shimmy": ("-c", "import shimmy"),
    "python -m shimmy --help": ("-m", "shimmy", "--help"),
    "hopf --config nes --Fz 150000 --no-cache": ("-m", "shimmy", "hopf", "--config", "nes", "--Fz", "150000",
                                                 "--no-cache"),
    "bifurcation --config nes --Fz 150000 --no-cache": ("-m", "shimmy", "bifurcation", "--config", "nes", "--Fz",
                                                        "150000", "--no-cache"),
    "curves --config original": ("-m", "shimmy", "curves", "--config", "original"),
    "map --config original, cached": MAP,
    "map --config original --json, cached": (*MAP, "--json"),
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
    os.environ["SHIMMY_CACHE_DIR"] = tempfile.mkdtemp(prefix="bench-start-")
    computed = seconds(MAP)  # computes the map and stores it: the repeats below read it
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
        print(f"  {name:<42}{median:7.3f} s  ({median - baseline:+.3f} s against the baseline)")
    print(f"  {'map --config original, computed (once)':<42}{computed:7.3f} s")
    print("in this process (kernels loaded; medians of 3):")
    for name, seconds_in_process in in_process().items():
        print(f"  {name:<42}{seconds_in_process:7.3f} s")


def in_process() -> dict[str, float]:
    """The diagram's and the curves' own work, timed in this process once its kernels are loaded."""
    from shimmy.analyses.diagrams.bifurcation import bifurcation
    from shimmy.analyses.diagrams.cycle_curves import cycle_curves

    def median(run) -> float:
        run()
        values = []
        for _ in range(3):
            clock = time.perf_counter()
            run()
            values.append(time.perf_counter() - clock)
        return statistics.median(values)

    return {"bifurcation nes at 150 kN": median(lambda: bifurcation("nes", 150e3)),
            "cycle_curves original": median(lambda: cycle_curves("original"))}


if __name__ == "__main__":
    main()
