"""Warm maps against cold maps (the live-maps issue's performance figures).

    python benchmarks/bench_warm_maps.py [--configs nes,nes_pd] [--steps e_p,r2,k_s,a_p] [--repeats 1]
    python benchmarks/bench_warm_maps.py --configs nes --walk 12 [--walk-step 0.02]

For each configuration: its cold map at the nominal design (the cached one), then for each slider
step (e_p +10 %, r2 -0.005 m, k_s +10 %, a_p +0.05; by name also a_p-, k_s- the other way and rho_p +10 %)
the cold map of the stepped design and its map
warmed from the nominal one, in the same process on the same pool (default executor: one worker
per core), ``--repeats`` times each, medians. Prints the seconds, the ratio warm / cold, how many
slices the warm map carried / computed again / added, and the share of equal shading cells
(warm against cold; the issue's bar: >= 99.5 %) and the differing cells away from every edge of the
cold map's regions (``map_shading.cells_off_edges``; the bar: none). Maps over V 1-200 m/s, Fz 10-900 kN, the
default resolution and grid.

``--breakdown``: each warm map's work besides, in seconds summed over its units as the workers ran them
(the Hopf curves; the fold and torus curve halves, with the points traced / guided; the slices computed
again or added; the rest: the Hopf scans, mode changes and links) and the pool's busy share of the wall time.

``--walk N``: a slider walk instead: N steps of e_p by ``--walk-step`` (relative) from the nominal
design, each map warmed from the one before (as the service warms from the nearest cached design),
printing each step's seconds and its slices carried / computed again / added: a slice is carried
only within ``CARRY_DISTANCE`` of the design its diagram was computed at (``design_distance``:
relative to the larger value), so the walk computes them all again at its first step farther than
that (+2 % steps: step 6, 0.112 from the nominal e_p; step 5 is 0.094). Configurations without the
NES (e_p not in their model) are left out.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time

import numpy as np

from shimmy.analyses.core.executors import describe, open_executor, worker_count
from shimmy.analyses.maps import map_shading, warm_map
from shimmy.analyses.maps.stability_map import stability_map
from shimmy.model.parameters import Parameters

STEPS = {"e_p": lambda p: {"e_p": round(p.nes.e_p * 1.1, 10)}, "r2": lambda p: {"r2": round(p.nes.r2 - 0.005, 10)},
         "k_s": lambda p: {"k_s": round(p.nes.k_s * 1.1, 10)}, "a_p": lambda p: {"a_p": round(p.pd.a_p + 0.05, 10)}}
#: other steps, by name with --steps: the slider's steps the other way, and the particle density
MORE_STEPS = {"a_p-": lambda p: {"a_p": round(p.pd.a_p - 0.05, 10)},
              "k_s-": lambda p: {"k_s": round(p.nes.k_s * 0.9, 10)},
              "rho_p": lambda p: {"rho_p": round(p.pd.rho_p * 1.1, 10)}}


#: --breakdown: the file each unit's (description, seconds in its worker) is appended to
UNIT_LOG = os.path.join(tempfile.gettempdir(), f"bench-warm-units-{os.getpid()}.jsonl")
_run_unit = warm_map.run_work_unit


def logged_unit(unit):
    """A warm map's unit run as before, its seconds in the worker appended to UNIT_LOG (a forked worker
    resolves this function in its copy of this module)."""
    clock = time.perf_counter()
    out = _run_unit(unit)
    with open(UNIT_LOG, "a") as f:
        f.write(json.dumps([warm_map.describe_work_unit(unit), time.perf_counter() - clock]) + "\n")
    return out


def breakdown(smap, wall: float) -> str:
    """The last warm map's work by kind (UNIT_LOG's lines since it was emptied)."""
    kinds = {"Hopf curves": 0.0, "curves": 0.0, "slices": 0.0, "rest": 0.0}
    with open(UNIT_LOG) as f:
        for line in f:
            what, seconds = json.loads(line)
            kind = ("Hopf curves" if what.startswith("Hopf curves") else "curves" if "nearby design again" in what
                    else "slices" if what.startswith("slice at") else "rest")
            kinds[kind] += seconds
    points = smap.warmed_from["curve_points"] if smap.warmed_from else {}
    work, n = sum(kinds.values()), worker_count()
    return (f"    work: {', '.join(f'{k} {v:.2f} s' for k, v in kinds.items())}; curve points traced/guided "
            f"{points.get('traced')}/{points.get('guided')}; pool busy {work / (n * wall):.0%} of {n} x {wall:.2f} s")


def timed(run):
    clock = time.perf_counter()
    out = run()
    return time.perf_counter() - clock, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configs", default="original,nes,pd,nes_pd")
    parser.add_argument("--steps", default=",".join(STEPS))
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--walk", type=int, default=0, help="steps of a walk in e_p (0: the slider steps)")
    parser.add_argument("--breakdown", action="store_true", help="each warm map's work by kind of unit")
    parser.add_argument("--walk-step", type=float, default=0.02, help="a walk's step, relative")
    args = parser.parse_args()
    if args.walk:
        if args.walk < 0 or args.walk_step <= 0:
            parser.error("--walk must be a number of steps >= 1 and --walk-step > 0")
        walk(args.configs.split(","), args.walk, args.walk_step)
        return
    unknown = [name for name in args.steps.split(",") if name not in {**STEPS, **MORE_STEPS}]
    if unknown:
        parser.error(f"--steps: unknown step(s) {', '.join(map(repr, unknown))}; known: "
                     f"{', '.join({**STEPS, **MORE_STEPS})}")
    print(f"machine: {os.cpu_count()} cores; executor: {describe()}")
    print(f"{'config':8} {'step':5} {'cold s':>8} {'warm s':>8} {'ratio':>6} {'carried/again/added':>20} "
          f"{'equal cells':>11} {'off edges':>9}")
    nominal = Parameters()
    if args.breakdown:
        warm_map.run_work_unit = logged_unit  # before the pool forks its workers
    with open_executor() as pool:
        stability_map("original", fz_range=(1.0e4, 3.0e4), resolution=3, executor=pool)  # workers warm
        for config in args.configs.split(","):
            base = stability_map(config, params=nominal, executor=pool)
            start = json.loads(json.dumps(base.warm_start()))
            for name in args.steps.split(","):
                params = nominal.with_overrides({**STEPS, **MORE_STEPS}[name](nominal))
                colds, warms = [], []
                for _ in range(args.repeats):
                    t, cold = timed(lambda: stability_map(config, params=params, executor=pool))
                    colds.append(t)
                    if args.breakdown:
                        open(UNIT_LOG, "w").close()
                    t, warm = timed(lambda: stability_map(config, params=params, executor=pool, warm_from=start))
                    warms.append(t)
                    if args.breakdown:
                        print(breakdown(warm, t), flush=True)
                c, w = statistics.median(colds), statistics.median(warms)
                slices = slice_counts(warm) or f"cold: {warm.warm_refused[:40]}"
                equal = float((np.array(cold.shading) == np.array(warm.shading)).mean())
                off = len(map_shading.cells_off_edges(cold.shading, warm.shading))
                print(f"{config:8} {name:5} {c:8.2f} {w:8.2f} {w / c:6.3f} {slices:>20} {100 * equal:10.2f}% "
                      f"{off:9d}", flush=True)
    if args.breakdown and os.path.exists(UNIT_LOG):
        os.remove(UNIT_LOG)


def slice_counts(smap) -> str:
    """A warm map's slices "carried/computed again/added"; empty for a map computed cold."""
    if smap.warmed_from is None:
        return ""
    s = smap.warmed_from["slices"]
    return f"{s['carried']}/{len(s['computed_again'])}/{len(s['added'])}"


def walk(configs: list[str], steps: int, step: float) -> None:
    """Each configuration's walk of ``steps`` e_p steps, each map warmed from the one before."""
    from shimmy.analyses.maps.warm_map import CARRY_DISTANCE
    from shimmy.model.configurations import affects

    configs = [c for c in configs if affects("e_p", c)]

    print(f"machine: {os.cpu_count()} cores; executor: {describe()}; CARRY_DISTANCE {CARRY_DISTANCE:g}")
    nominal = Parameters()
    with open_executor() as pool:
        stability_map("original", fz_range=(1.0e4, 3.0e4), resolution=3, executor=pool)  # workers warm
        for config in configs:
            t, here = timed(lambda: stability_map(config, params=nominal, executor=pool))
            print(f"{config:8} step  0 e_p {nominal.nes.e_p:.6g}: cold {t:6.2f} s", flush=True)
            times = []
            for k in range(1, steps + 1):
                params = nominal.with_overrides({"e_p": round(nominal.nes.e_p * (1.0 + step) ** k, 10)})
                start = json.loads(json.dumps(here.warm_start()))
                t, here = timed(lambda: stability_map(config, params=params, executor=pool, warm_from=start))
                times.append(t)
                counts = slice_counts(here)
                slices = f"{counts} carried/again/added" if counts else f"cold: {here.warm_refused}"
                print(f"{config:8} step {k:2d} e_p {params.nes.e_p:.6g}: {t:6.2f} s  {slices}", flush=True)
            print(f"{config:8} walk: median {statistics.median(times):.2f} s, longest {max(times):.2f} s, "
                  f"total {sum(times):.1f} s", flush=True)


if __name__ == "__main__":
    main()
