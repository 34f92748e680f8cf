"""Design-decision benchmarks (the design issue's performance figures).

    python benchmarks/bench_design.py [--repeats 5] [--skip-dask]

* ``sensitivity``: the Hopf speeds' derivatives with respect to all parameters of one configuration at
  150 kN (implicit differentiation; includes locating the Hopf points), median of ``--repeats``
  in-process runs after one warm-up (target <= 50 ms); beside it the same derivatives by central
  differences of re-solved Hopf points (two eigenvalue scans per parameter), ratio in one process;
  the minimum shimmy load's and the amplitude's derivatives against one bifurcation diagram;
* ``optimise``: the minimum shimmy load of ``nes`` over r2, e_p, k_s, r3 (8 Sobol starts, 2 SLSQP
  runs) on the default executor (a local process pool, one worker per core; target <= 2 minutes),
  in the calling process, and on a loopback Dask cluster of 1 and of 2 single-threaded workers
  (speed-up 2 vs 1);
* ``robustness``: 256 samples of ``nes_pd`` under 5 % tolerances on the tyre constants and the NES
  spring, on the default executor.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from shimmy.analyses.diagrams.bifurcation import BifurcationOptions, bifurcation
from shimmy.analyses.core.executors import InlineExecutor, describe, open_executor
from shimmy.analyses.decisions.optimise import optimise
from shimmy.analyses.decisions.robustness import robustness
from shimmy.analyses.decisions.sensitivity import sensitivity
from shimmy.analyses.core.stability import hopf_points
from shimmy.model.parameters import PARAMETER_SPECS, Parameters
from shimmy.service.dask_cluster import loopback_cluster

CONFIGS = ("original", "nes", "pd", "nes_pd")
TOLERANCES = [f"{n}=0.05" for n in ("k_lam", "c_lam", "L", "h", "k_a", "alpha_m", "k_s")]


def median_time(fn, repeats: int) -> tuple[float, list[float]]:
    runs = []
    for _ in range(repeats):
        clock = time.perf_counter()
        fn()
        runs.append(time.perf_counter() - clock)
    return statistics.median(runs), runs


def finite_differences(config: str) -> None:
    p = Parameters()
    for name in PARAMETER_SPECS:
        v = float(getattr(p, name))
        h = 1e-5 * (abs(v) or 1.0)
        for value in (v + h, v - h):
            try:
                hopf_points(config, 150e3, params=p.with_overrides({name: value}), v_range=(1, 200))
            except Exception:  # a range end: the benchmark only times the work
                hopf_points(config, 150e3, params=p, v_range=(1, 200))


def sensitivities(repeats: int) -> None:
    print(f"\nsensitivities at 150 kN, all {len(PARAMETER_SPECS)} parameters, medians of {repeats} runs:")
    print(f"  {'config':<8}{'Hopf speeds (ms)':>18}{'by differences (ms)':>21}{'ratio':>7}"
          f"{'min shimmy (s)':>16}{'amplitude (s)':>15}{'one diagram (s)':>17}")
    for c in CONFIGS:
        sensitivity(c, 150e3, amplitude=False, min_shimmy=False)  # warm
        hopf, _ = median_time(lambda c=c: sensitivity(c, 150e3, amplitude=False, min_shimmy=False), repeats)
        fd, _ = median_time(lambda c=c: finite_differences(c), max(1, repeats // 2))
        s = sensitivity(c, 150e3)
        diagram, _ = median_time(lambda c=c: bifurcation(c, 150e3, v_range=(1, 200), options=BifurcationOptions(
            mesh_check=False)), max(1, repeats // 2))
        print(f"  {c:<8}{1e3 * hopf:>18.1f}{1e3 * fd:>21.1f}{fd / hopf:>7.1f}{s.elapsed_s['min_shimmy_Fz']:>16.2f}"
              f"{s.elapsed_s['max_psi']:>15.2f}{diagram:>17.2f}")
    print("  target: Hopf speeds <= 50 ms")


def optimisations(repeats: int, skip_dask: bool) -> None:
    def run(executor):
        return optimise("nes", "min_shimmy_Fz", parameters=("r2", "e_p", "k_s", "r3"), executor=executor)

    print(f"\noptimise nes, min shimmy load over r2, e_p, k_s, r3, medians of {repeats}:")
    results = {}
    with open_executor() as pool:
        t, runs = median_time(lambda: results.setdefault("pool", run(pool)), repeats)
    r = results["pool"]
    print(f"  pool ({describe()}): median {t:6.1f} s (runs {', '.join(f'{x:.1f}' for x in runs)})  target <= 120 s")
    print(f"    optimum {r.objective_value / 1e3:.3f} kN (nominal {r.nominal_objective / 1e3:.3f} kN, original "
          f"{r.figures['original']['min_shimmy_Fz'] / 1e3:.3f} kN), {r.evaluations} evaluations, design "
          + ", ".join(f"{n} = {v:.6g}" for n, v in r.design.items()))
    serial, runs = median_time(lambda: run(InlineExecutor()), repeats)
    print(f"  serial: median {serial:6.1f} s (runs {', '.join(f'{x:.1f}' for x in runs)}); ratio serial / pool "
          f"{serial / t:.2f}")
    if skip_dask:
        return
    times = {}
    for n in (1, 2):
        with loopback_cluster(n_workers=n) as address, open_executor(scheduler=address) as ex:
            run(ex)  # the workers' imports and numba caches
            times[n], runs = median_time(lambda ex=ex: run(ex), repeats)
        print(f"  Dask {n} worker(s): median {times[n]:6.1f} s (runs {', '.join(f'{x:.1f}' for x in runs)})")
    print(f"  Dask speed-up 2 vs 1 worker: {times[1] / times[2]:.2f}")


def robust(repeats: int) -> None:
    with open_executor() as pool:
        t, runs = median_time(lambda: robustness("nes_pd", TOLERANCES, samples=256, executor=pool), repeats)
    print(f"\nrobustness nes_pd, 256 samples, 5 % on {', '.join(x.split('=')[0] for x in TOLERANCES)}: median "
          f"{t:.2f} s (runs {', '.join(f'{x:.2f}' for x in runs)})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--skip-dask", action="store_true")
    args = parser.parse_args()
    print(f"machine: {os.cpu_count()} cores; default executor: {describe()}")
    sensitivities(args.repeats)
    optimisations(max(1, args.repeats // 2 + 1), args.skip_dask)
    robust(args.repeats)


if __name__ == "__main__":
    main()
