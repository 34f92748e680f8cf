"""Benchmark of disturbance margins, printed as a table.

At `original` (50 m/s, 550 kN), where a lateral and a torsional cycle coexist, on the local process pool
(opened once; medians of N after one warm-up call, which loads the compiled code): the smallest yaw kick
to each attractor (``margins``, direction psi), the smallest energy over all directions (direction
energy) and basin fractions of 200 kicks up to 0.2 rad. Each with the one-parameter diagram at the load
kept for the process (as repeated questions at one load have it) and with it computed afresh.

Targets: the yaw margin <= 1 s, over all directions <= 10 s.

    python benchmarks/bench_margins.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import time

from shimmy.analyses.core.executors import describe, open_executor
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    with open_executor() as pool:
        clock = time.perf_counter()
        margins(*POINT, executor=pool)
        print(f"first call (compiled code loaded, diagram computed): {time.perf_counter() - clock:.2f} s on "
              f"{describe()}")
        cases = {"yaw kick (psi)": lambda: margins(*POINT, direction="psi", executor=pool),
                 "all directions (energy)": lambda: margins(*POINT, direction="energy", executor=pool),
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
