"""Stability-map benchmarks (issue 4's performance figures).

    python benchmarks/bench_maps.py [--repeats 3] [--resolution 40] [--dask-resolution 20]

* ``one map``: ``stability_map("original")`` over V 1-200 m/s, Fz 10-900 kN, ``--resolution``
  Fz slices x 100 speeds, cold (no result cache exists in the analyses; the numba integrator's
  on-disk compile cache is warm, as it is after installation), on the default executor (a
  local process pool, one worker per core); median of ``--repeats`` runs (target <= 60 s);
* ``serial``: the same map in the calling process (InlineExecutor), the baseline in the same
  process; ``ratio`` = serial / pool;
* ``four maps``: the four configurations one after the other (target <= 4 min);
* ``dask``: one map at ``--dask-resolution`` slices on a loopback Dask cluster of 1 and of 2
  single-threaded workers (separate processes, no nanny), and the speed-up 2 vs 1; the
  first run on a fresh cluster includes the workers' imports.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from shimmy.analyses.executors import InlineExecutor, describe, open_executor
from shimmy.service.dask_cluster import loopback_cluster
from shimmy.analyses.stability_map import stability_map

CONFIGS = ("original", "nes", "pd", "nes_pd")
PLANE = dict(v_range=(1.0, 200.0), fz_range=(1.0e4, 9.0e5))


def timed(config: str, resolution: int, executor=None) -> tuple[float, object]:
    clock = time.perf_counter()
    smap = stability_map(config, resolution=resolution, executor=executor, **PLANE)
    return time.perf_counter() - clock, smap


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--resolution", type=int, default=40)
    parser.add_argument("--dask-resolution", type=int, default=20)
    parser.add_argument("--skip-dask", action="store_true")
    parser.add_argument("--only-dask", action="store_true")
    args = parser.parse_args()
    print(f"machine: {os.cpu_count()} cores; default executor: {describe()}")
    if not args.only_dask:
        local(args)
    if not args.skip_dask:
        dask(args)


def local(args) -> None:
    pool_runs, serial_runs = [], []
    for _ in range(args.repeats):
        t, smap = timed("original", args.resolution)
        pool_runs.append(t)
        t, _ = timed("original", args.resolution, InlineExecutor())
        serial_runs.append(t)
    pool, serial = statistics.median(pool_runs), statistics.median(serial_runs)
    print(f"\none map (original, {args.resolution} slices x {len(smap.V)} speeds), {args.repeats} runs:")
    print(f"  pool   median {pool:6.1f} s  (runs {', '.join(f'{t:.1f}' for t in pool_runs)})  target <= 60 s")
    print(f"  serial median {serial:6.1f} s  (runs {', '.join(f'{t:.1f}' for t in serial_runs)})")
    print(f"  ratio serial / pool {serial / pool:.2f}")

    print(f"\nfour maps ({args.resolution} slices each), one after the other:")
    print(f"  {'config':<8}{'s':>7}{'min shimmy Fz (kN)':>20}{'slices':>8}{'curves H/LPC/NS':>17}")
    total = 0.0
    with open_executor() as pool_executor:
        for c in CONFIGS:
            t, smap = timed(c, args.resolution, pool_executor)
            total += t
            low = "-" if smap.min_shimmy_Fz is None else f"{smap.min_shimmy_Fz / 1e3:.2f}"
            print(f"  {c:<8}{t:7.1f}{low:>20}{len(smap.Fz):>8}"
                  f"{len(smap.hopf.curves):>9}/{len(smap.fold_curves)}/{len(smap.torus_curves)}")
    print(f"  total {total:.1f} s  target <= 240 s")


def dask(args) -> None:
    print(f"\nDask on loopback (original, {args.dask_resolution} slices):")
    times = {}
    for n in (1, 2):
        with loopback_cluster(n_workers=n) as address, open_executor(scheduler=address) as ex:
            runs = [timed("original", args.dask_resolution, ex)[0] for _ in range(args.repeats)]
        times[n] = statistics.median(runs)
        print(f"  {n} worker(s): median {times[n]:6.1f} s  (runs {', '.join(f'{t:.1f}' for t in runs)})")
    print(f"  speed-up 2 vs 1 worker: {times[1] / times[2]:.2f}")


if __name__ == "__main__":
    main()
