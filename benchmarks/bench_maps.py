"""Stability-map benchmarks (the maps-on-curves issue's performance figures).

    python benchmarks/bench_maps.py [--repeats 3] [--resolution 10] [--baseline 40] [--dask-resolution 10]

* ``one map``: ``stability_map("original")`` over V 1-200 m/s, Fz 10-900 kN, ``--resolution``
  classified slices (and those the map adds through regions they miss) x 100 speeds, cold (no
  result cache exists in the analyses; the numba integrator's on-disk compile cache is warm, as
  it is after installation), on the default executor (a local process pool, one worker per
  core); median of ``--repeats`` runs (target <= 10 s on 2 cores);
* ``slice map``: the same map classified on ``--baseline`` slices (40: the slice-by-slice map
  the product had before its regions were read off the curves, whose cost is the slices'),
  in the same process; ``speed-up`` = slice map / map;
* ``serial``: the map in the calling process (InlineExecutor); ``ratio`` = serial / pool;
* ``four maps``: the four configurations on one pool, ``stability_maps`` (their units all
  through the pool at once, as ``python -m shimmy metrics`` computes them; target <= 30 s), and
  one after the other (``stability_map`` each) for the ratio;
* ``dask``: one map on a loopback Dask cluster of 1 and of 2 single-threaded workers (separate
  processes, no nanny), and the speed-up 2 vs 1; the first run on a fresh cluster includes the
  workers' imports.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from shimmy.analyses.core.executors import InlineExecutor, describe, open_executor
from shimmy.service.dask_cluster import loopback_cluster
from shimmy.analyses.maps.stability_map import stability_map, stability_maps

CONFIGS = ("original", "nes", "pd", "nes_pd")
PLANE = dict(v_range=(1.0, 200.0), fz_range=(1.0e4, 9.0e5))


def timed(config: str, resolution: int, executor=None) -> tuple[float, object]:
    clock = time.perf_counter()
    smap = stability_map(config, resolution=resolution, executor=executor, **PLANE)
    return time.perf_counter() - clock, smap


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--resolution", type=int, default=10)
    parser.add_argument("--baseline", type=int, default=40)
    parser.add_argument("--dask-resolution", type=int, default=10)
    parser.add_argument("--skip-dask", action="store_true")
    parser.add_argument("--only-dask", action="store_true")
    parser.add_argument("--only-four", action="store_true", help="only the four maps (no one-map figures, no Dask)")
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    print(f"machine: {os.cpu_count()} cores; default executor: {describe()}")
    if args.only_four:
        four(args)
        return
    if not args.only_dask:
        local(args)
        four(args)
    if not args.skip_dask:
        dask(args)


def local(args) -> None:
    pool_runs, base_runs, serial_runs = [], [], []
    for _ in range(args.repeats):
        t, smap = timed("original", args.resolution)
        pool_runs.append(t)
        base_runs.append(timed("original", args.baseline)[0])
        serial_runs.append(timed("original", args.resolution, InlineExecutor())[0])
    pool, base, serial = (statistics.median(r) for r in (pool_runs, base_runs, serial_runs))
    runs = lambda r: ", ".join(f"{t:.1f}" for t in r)  # noqa: E731
    print(f"\none map (original, {args.resolution} slices asked, {len(smap.Fz)} classified, "
          f"{len(smap.shading_Fz)} x {len(smap.V)} grid), {args.repeats} runs:")
    print(f"  map        median {pool:6.1f} s  (runs {runs(pool_runs)})  target <= 10 s")
    print(f"  slice map  median {base:6.1f} s  (runs {runs(base_runs)})  {args.baseline} slices")
    print(f"  speed-up slice map / map {base / pool:.2f}")
    print(f"  serial     median {serial:6.1f} s  (runs {runs(serial_runs)});  ratio serial / pool {serial / pool:.2f}")



def four(args) -> None:
    runs = lambda r: ", ".join(f"{t:.1f}" for t in r)  # noqa: E731
    if args.only_four:  # the pool's workers fork from this process: load the compiled kernels here once
        stability_map("original", resolution=2, executor=InlineExecutor(), **PLANE)
    print(f"\nfour maps ({args.resolution} slices asked each) on one pool, medians of {args.repeats}:")
    print(f"  {'config':<8}{'s':>7}{'min shimmy Fz (kN)':>20}{'slices':>8}{'curves H/LPC/NS':>17}{'regions':>9}")
    together, apart = [], []
    times: dict[str, list[float]] = {c: [] for c in CONFIGS}
    last = {}
    with open_executor() as pool_executor:
        for _ in range(args.repeats):
            clock = time.perf_counter()
            maps = stability_maps(CONFIGS, resolution=args.resolution, executor=pool_executor, **PLANE)
            together.append(time.perf_counter() - clock)
            total = 0.0
            for c in CONFIGS:
                t, last[c] = timed(c, args.resolution, pool_executor)
                times[c].append(t)
                total += t
            apart.append(total)
    for c, smap in last.items():
        low = "-" if smap.min_shimmy_Fz is None else f"{smap.min_shimmy_Fz / 1e3:.2f}"
        print(f"  {c:<8}{statistics.median(times[c]):7.1f}{low:>20}{len(smap.Fz):>8}"
              f"{len(smap.hopf.curves):>9}/{len(smap.fold_curves)}/{len(smap.torus_curves)}{len(smap.regions):>9}")
    same = all(m.shading == last[c].shading for m, c in zip(maps, CONFIGS, strict=True))
    print(f"  one after the other: total median {statistics.median(apart):.1f} s (runs {runs(apart)})")
    print(f"  together (stability_maps): median {statistics.median(together):.1f} s (runs {runs(together)})"
          f"  target <= 30 s;  ratio apart / together {statistics.median(apart) / statistics.median(together):.2f};"
          f"  same shading as apart: {same}")


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
