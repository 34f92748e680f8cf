"""Continuation benchmarks: one bifurcation diagram per configuration and the Hopf curves.

    python benchmarks/bench_continuation.py [--repeats 5]

Per configuration at Fz = 150 kN, V 1-200 m/s (all periodic branches, simulation seeds on):

* ``cli s``: wall time of ``python -m shimmy bifurcation ... --json`` in a fresh process
  (process start and imports included; the target is <= 3 s, AUTO-07p's ~1 s is the goal);
* ``in-process s``: ``bifurcation()`` alone, warm;
* ``sweep s`` and ``ratio``: the baseline run in the same process, a brute-force amplitude
  sweep by time simulation (40 speeds x 60 s, the way one would do it without continuation),
  and its time over the diagram's;
* mesh (ntst x ncol, the final adapted mesh), continuation steps, max |psi| of stable cycles
  and its change under mesh doubling (the 1e-4 rad convergence requirement).

Hopf curves: ``hopf_curves()`` over V 1-500 m/s, Fz 10-900 kN, time per curve (target <= 1 s).
Medians over ``--repeats`` runs.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

import numpy as np

from shimmy.analyses.diagrams.bifurcation import bifurcation
from shimmy.analyses.diagrams.hopf_curves import hopf_curves
from shimmy.analyses.core.simulation import simulate

CONFIGS = ("original", "nes", "pd", "nes_pd")
FZ = 150e3


def cli_seconds(config: str) -> float:
    clock = time.perf_counter()
    subprocess.run([sys.executable, "-m", "shimmy", "bifurcation", "--config", config, "--Fz", str(FZ),
                    "--v-min", "1", "--v-max", "200", "--json"], check=True, capture_output=True,
                   env={**os.environ, "PYTHONHASHSEED": "0"})
    return time.perf_counter() - clock


def sweep_seconds(config: str) -> float:
    clock = time.perf_counter()
    for V in np.linspace(1, 200, 40):
        simulate(config, float(V), FZ, t_end=60.0)
    return time.perf_counter() - clock


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    r = args.repeats
    for config in CONFIGS:  # warm the numba cache and imports
        bifurcation(config, FZ, v_range=(1, 200))
    print(f"bifurcation diagrams at Fz = {FZ / 1e3:g} kN, V 1-200 m/s; medians of {r} runs")
    print(f"{'config':<9}{'cli s':>7}{'in-proc s':>11}{'sweep s':>9}{'ratio':>7}{'mesh':>8}{'steps':>7}"
          f"{'max psi rad':>13}{'mesh change':>13}")
    for config in CONFIGS:
        cli = statistics.median(cli_seconds(config) for _ in range(r))
        inproc, result = [], None
        for _ in range(r):
            clock = time.perf_counter()
            result = bifurcation(config, FZ, v_range=(1, 200))
            inproc.append(time.perf_counter() - clock)
        sweep = statistics.median(sweep_seconds(config) for _ in range(max(1, r // 2)))
        t = statistics.median(inproc)
        periodic = [b for b in result.branches if b.kind == "periodic"]
        mesh = f"{periodic[0].raw.ntst}x{periodic[0].raw.ncol}" if periodic else "-"
        steps = sum(b.steps for b in result.branches)
        change = result.mesh_check["change"] if result.mesh_check else float("nan")
        print(f"{config:<9}{cli:>7.2f}{t:>11.3f}{sweep:>9.2f}{sweep / t:>6.1f}x{mesh:>8}{steps:>7}"
              f"{result.max_psi:>13.6f}{change:>13.1e}")
    print()
    print(f"Hopf curves over V 1-500 m/s, Fz 10-900 kN; medians of {r} runs")
    print(f"{'config':<9}{'curves':>7}{'total s':>9}{'per curve s':>13}{'steps':>7}{'GH':>4}{'min Fz kN':>11}")
    for config in CONFIGS:
        times, res = [], None
        for _ in range(r):
            clock = time.perf_counter()
            res = hopf_curves(config)
            times.append(time.perf_counter() - clock)
        t = statistics.median(times)
        n = len(res.curves)
        low = res.fz_minimum["Fz"] / 1e3 if res.fz_minimum else float("nan")
        print(f"{config:<9}{n:>7}{t:>9.3f}{t / max(n, 1):>13.3f}{sum(c.steps for c in res.curves):>7}"
              f"{len(res.gh_points):>4}{low:>11.2f}")


if __name__ == "__main__":
    main()
