"""Benchmark of ground runs, printed as a table.

A 60 s ground run of each configuration (median of N after one warm-up run, which loads or
compiles the numba code) for two 60 s profiles: the taxi preset (60 s by default) and a slow
take-off (acceleration 1.25 m/s^2 from 5 to 80 m/s, 60 s); the time covers the whole report
(integration, envelopes, time in shimmy, peaks, the Hopf crossings by the eigenvalue scan) with
the integration alone beside it. Then the four-configuration comparison of each profile.

Targets: one configuration <= 0.3 s, the four-configuration comparison <= 1.5 s.

    python benchmarks/bench_ground_run.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import time

from shimmy.analyses.ground.ground_profiles import preset
from shimmy.analyses.ground.ground_run import ground_run, ground_runs
from shimmy.model.configurations import ALL_CONFIGURATIONS

PROFILES = {"taxi (60 s)": preset("taxi"),
            "take-off (60 s)": preset("takeoff", {"acceleration": 1.25})}


def _median(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        clock = time.perf_counter()
        fn()
        times.append(time.perf_counter() - clock)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    clock = time.perf_counter()
    ground_run("nes_pd", PROFILES["taxi (60 s)"])
    print(f"first call (numba cache load or compile): {time.perf_counter() - clock:.2f} s")
    print(f"{'profile':<17}{'configuration':<15}{'median (s)':>11}{'integration (s)':>17}{'steps':>8}"
          f"{'in shimmy (s)':>15}")
    for name, profile in PROFILES.items():
        assert abs(profile.duration - 60.0) < 1e-9, profile.duration
        for config in ALL_CONFIGURATIONS:
            run = ground_run(config, profile)
            median = _median(lambda c=config, p=profile: ground_run(c, p), args.repeats)
            print(f"{name:<17}{config.value:<15}{median:>11.3f}{run.counters['integration_ms'] / 1e3:>17.3f}"
                  f"{run.counters['steps']:>8}{run.time_in_shimmy_s:>15.2f}")
        median = _median(lambda p=profile: ground_runs(p), args.repeats)
        print(f"{name:<17}{'all four':<15}{median:>11.3f}")
    print("targets: one configuration <= 0.3 s, the four compared <= 1.5 s")


if __name__ == "__main__":
    main()
