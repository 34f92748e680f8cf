"""Benchmark: every fold and torus curve of cycles of a configuration, and the Hopf curves with
their codimension-2 points.

    python benchmarks/bench_cycle_curves.py [--repeats 3] [--configs original,nes]

Per configuration over V 1-200 m/s, Fz 10-900 kN:

* ``hopf s``: ``hopf_curves()`` with GH and double-Hopf points located (target <= 0.5 s);
* ``curves s``: ``cycle_curves()`` -- finding the starts (Hopf curves, branches beside GH and
  double-Hopf points, three one-parameter diagrams, large-amplitude starts) and continuing each
  curve to its ends (target <= 5 s);
* ``diagram s`` and ``ratio``: the baseline in the same process, one one-parameter diagram at
  450 kN, and the curves' time over it;
* the number of fold / torus curves, of points on them, and of curve starts tried.

Medians over ``--repeats`` runs, after one warm-up run per configuration (numba cache, imports).
"""

from __future__ import annotations

import argparse
import statistics
import time

from shimmy.analyses.diagrams.bifurcation import bifurcation
from shimmy.analyses.diagrams.cycle_curves import cycle_curves
from shimmy.analyses.diagrams.hopf_curves import hopf_curves


def timed(fn, *args, **kwargs):
    clock = time.perf_counter()
    out = fn(*args, **kwargs)
    return time.perf_counter() - clock, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--configs", default="original,nes,pd,nes_pd")
    args = parser.parse_args()
    print(f"{'config':<9}{'hopf s':>8}{'curves s':>10}{'diagram s':>11}{'ratio':>7}{'folds':>7}{'tori':>6}"
          f"{'points':>8}{'starts':>8}")
    for config in args.configs.split(","):
        cycle_curves(config)  # warm-up
        hopf, curves, diagram = [], [], []
        result = None
        for _ in range(args.repeats):
            hopf.append(timed(hopf_curves, config, v_range=(1.0, 200.0))[0])
            seconds, result = timed(cycle_curves, config)
            curves.append(seconds)
            diagram.append(timed(bifurcation, config, 450e3)[0])
        data = result.to_dict()
        points = sum(len(c) for c in data["fold_curves"] + data["torus_curves"])
        c_med, d_med = statistics.median(curves), statistics.median(diagram)
        print(f"{config:<9}{statistics.median(hopf):>8.2f}{c_med:>10.2f}{d_med:>11.2f}{c_med / d_med:>7.1f}"
              f"{len(data['fold_curves']):>7}{len(data['torus_curves']):>6}{points:>8}{result.starts_tried:>8}")


if __name__ == "__main__":
    main()
