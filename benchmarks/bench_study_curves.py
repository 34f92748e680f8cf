"""Study curves against a sampled study, in one process.

    python benchmarks/bench_study_curves.py [--config nes] [--param e_p]

Prints the time of the exact curves hopf_V_start and hopf_V_end of one configuration over the
parameter's whole range (:func:`~shimmy.analyses.decisions.study_curves.hopf_speed_curves`, target
<= 2 s) against a sampled study of 9 values of it (one bifurcation diagram each, inline), and the
max_psi curve's two passes (:mod:`~shimmy.analyses.decisions.max_psi_curve`): its grid diagrams
and the maxima followed between them, inline.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from shimmy.analyses.core.executors import InlineExecutor
from shimmy.analyses.decisions import studies
from shimmy.analyses.decisions.max_psi_curve import grid
from shimmy.analyses.decisions.studies import study
from shimmy.analyses.diagrams.options import BifurcationOptions
from shimmy.model.parameters import DEFAULT_FZ, DIAGRAM_V_RANGE
from shimmy.analyses.decisions.study_curves import hopf_speed_curves, parameter_range
from shimmy.model.parameters import Parameters


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="nes")
    parser.add_argument("--param", default="e_p")
    args = parser.parse_args()
    hopf_speed_curves(args.config, args.param)  # warm-up: compiled kernels loaded
    clock = time.perf_counter()
    curves = hopf_speed_curves(args.config, args.param).study_curves()
    curve_s = time.perf_counter() - clock
    lo, hi = parameter_range(args.param, Parameters())
    clock = time.perf_counter()
    study(args.param, [float(v) for v in np.linspace(lo, hi, 9)], configs=[args.config],
          executor=InlineExecutor())  # its sampled rows, and its curves as above
    sampled_s = time.perf_counter() - clock
    print(f"study curve {args.config} in {args.param} ({len(curves[0].p)} exact points): {curve_s:.3f} s "
          f"(target <= 2 s); sampled study of 9 values (with its curves): {sampled_s:.2f} s; "
          f"ratio {sampled_s / curve_s:.0f}x")
    base, options = Parameters(), BifurcationOptions(mesh_check=False)
    clock = time.perf_counter()
    rows = [studies._unit((args.config, {args.param: theta}, DEFAULT_FZ, *DIAGRAM_V_RANGE, base, options))
            for theta in grid(args.param, base)]
    grid_s = time.perf_counter() - clock
    orbits = studies._orbits(rows, [args.param])
    clock = time.perf_counter()
    follows = studies._follow_maxima(args.param, {args.config: rows}, orbits, DEFAULT_FZ, DIAGRAM_V_RANGE, base,
                                     options, InlineExecutor(), None, None)[args.config]
    follow_s = time.perf_counter() - clock
    points = sum(len(f["points"]) for f in follows.values())
    print(f"max_psi curve {args.config} in {args.param}: {len(rows)} grid diagrams {grid_s:.2f} s, "
          f"{points} followed points {follow_s:.2f} s ({1e3 * follow_s / max(points, 1):.0f} ms each)")


if __name__ == "__main__":
    main()
