"""Benchmark of disturbance margins, printed as a table.

At `original` (50 m/s, 550 kN), where a lateral and a torsional cycle coexist, on the local process pool
(opened once; medians of N after one warm-up call, which loads the compiled code): the smallest yaw kick
to each attractor (``margins``, direction psi), the same from the lateral cycle the standard start
reaches (origin standard_attractor, 8 phases and the best located between them), along a mix of yaw angle
and rate, the smallest energy over all directions (direction energy) and basin fractions of 200 kicks up
to 0.2 rad. Each with the one-parameter diagram at the load
kept for the process (as repeated questions at one load have it) and with it computed afresh.

Then margin maps (``margin_map``): for original and nes, the smallest yaw kick to torsional shimmy in every cell of
the default plane (V 1-200 m/s, Fz 10-900 kN, 20 x 10 cells) where a torsional cycle coexists with another
attractor, cold (no diagram kept: each load's diagram computed in its unit), on the local pool; then one of them
on a loopback Dask cluster of 1 and of 2 single-threaded workers (separate processes), and the speed-up 2 vs 1.

Targets: the yaw margin <= 1 s, over all directions <= 10 s, a margin map of one configuration <= 60 s on 2 cores.

    python benchmarks/bench_margins.py [--repeats 5] [--map-repeats 2] [--skip-dask] [--only-maps]
"""

from __future__ import annotations

import argparse
import statistics
import time

from shimmy.analyses.core.executors import describe, open_executor
from shimmy.analyses.maps.margin_map import margin_map
from shimmy.analyses.maps.margins import basins, diagram_at, margins

POINT = ("original", 50.0, 550e3)


def _median(fn, repeats: int, fresh: bool) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        if fresh:
            diagram_at.cache_clear()
        clock = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - clock)
    return statistics.median(times), result


def _fresh_map(config: str, executor) -> tuple[float, object]:
    """(seconds, result) of a margin map with no diagram kept in this process (the pool's workers keep theirs
    between calls: a fresh pool per call)."""
    diagram_at.cache_clear()
    clock = time.perf_counter()
    result = margin_map(config, executor=executor)
    return time.perf_counter() - clock, result


def maps(repeats: int) -> None:
    print(f"\nmargin maps, 20 x 10 cells of V 1-200 m/s, Fz 10-900 kN, cold, a fresh {describe()} per run, "
          f"medians of {repeats}:")
    print(f"{'config':<10}{'s':>7}{'cells':>7}{'multistable':>13}{'bistable':>10}{'computed':>10}{'runs':>7}  "
          "margins (rad)")
    for config in ("original", "nes"):
        times, result = [], None
        for _ in range(repeats):
            with open_executor() as pool:
                t, result = _fresh_map(config, pool)
            times.append(t)
        c = result.to_dict()["counts"]
        values = [p["margin"] for p in result.points if p["margin"]]
        span = f"0 in {c['zero']} cells, {min(values):.3g} to {max(values):.3g} elsewhere" if values else "-"
        print(f"{config:<10}{statistics.median(times):7.1f}{c['cells']:>7}{c['multistable']:>13}{c['bistable']:>10}"
              f"{c['computed']:>10}{c['runs']:>7}  {span}; {c['not_reached']} not reached")
    print("target: <= 60 s per configuration on 2 cores")


def _forget() -> None:
    """Run on each Dask worker: forget the diagrams kept (the next map computes its own)."""
    diagram_at.cache_clear()


def dask_maps(repeats: int) -> None:
    from shimmy.service.dask_cluster import loopback_cluster

    print("\nmargin map of original on a loopback Dask cluster (single-threaded workers, separate processes):")
    times = {}
    for n in (1, 2):
        with loopback_cluster(n_workers=n) as address, open_executor(scheduler=address) as ex:
            margin_map("original", executor=ex, n_v=2, n_fz=2, v_range=(40.0, 120.0), fz_range=(5e5, 9e5))  # warm-up
            runs = []
            for _ in range(repeats):
                ex._client.run(_forget)  # the workers' kept diagrams: cold, as on the local pool
                runs.append(_fresh_map("original", ex)[0])
        times[n] = statistics.median(runs)
        print(f"  {n} worker(s): median {times[n]:6.1f} s  (runs {', '.join(f'{t:.1f}' for t in runs)})")
    print(f"  speed-up 2 vs 1 worker: {times[1] / times[2]:.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--map-repeats", type=int, default=2)
    parser.add_argument("--skip-dask", action="store_true")
    parser.add_argument("--only-maps", action="store_true", help="only the margin maps (and Dask, unless skipped)")
    args = parser.parse_args()
    if not args.only_maps:
        points(args)
    maps(args.map_repeats)
    if not args.skip_dask:
        dask_maps(args.map_repeats)


def points(args) -> None:
    with open_executor() as pool:
        clock = time.perf_counter()
        margins(*POINT, executor=pool)
        print(f"first call (compiled code loaded, diagram computed): {time.perf_counter() - clock:.2f} s on "
              f"{describe()}")
        cases = {"yaw kick (psi)": lambda: margins(*POINT, direction="psi", executor=pool),
                 "all directions (energy)": lambda: margins(*POINT, direction="energy", executor=pool),
                 "yaw kick, from the cycle": lambda: margins(*POINT, direction="psi", origin="standard_attractor",
                                                             executor=pool),
                 "mix psi=0.01,dpsi=0.1": lambda: margins(*POINT, direction="mix", mix="psi=0.01,dpsi=0.1",
                                                          executor=pool),
                 "basins, 200 kicks": lambda: basins(*POINT, samples=200, executor=pool)}
        print(f"{'question':<25}{'diagram kept (s)':>17}{'diagram fresh (s)':>19}{'runs':>7}  answer")
        for name, fn in cases.items():
            kept, result = _median(fn, args.repeats, fresh=False)
            fresh, _ = _median(fn, max(1, args.repeats // 2), fresh=True)
            data = result.to_dict()
            if "basin" in data["attractors"][0]:
                answer = ", ".join(f"{a['mode']} {100 * a['basin']['fraction']:.1f} %" for a in data["attractors"])
            else:
                answer = ", ".join(f"{a['mode']} {a['min_disturbance']['value']:.5g} {a['min_disturbance']['unit']}"
                                   for a in data["attractors"])
            print(f"{name:<25}{kept:>17.3f}{fresh:>19.3f}{data['runs']:>7}  {answer}")
    print("targets: yaw kick <= 1 s, all directions <= 10 s")


if __name__ == "__main__":
    main()
