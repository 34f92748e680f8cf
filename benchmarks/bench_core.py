"""Benchmark of the physics core (issue: physics core), printed as a table.

For each configuration at operating point A (V = 30 m/s, Fz = 150 kN), 60 s from
psi = 0.001 rad:

* shimmy.simulate (compiled Dormand-Prince, rtol 1e-7): median of N runs after one
  warm-up run (the warm-up loads or compiles the numba code; its time is reported
  separately as "first call");
* the plain reference: scipy solve_ivp(method="LSODA", rtol=1e-8, atol=1e-10,
  max_step=0.005) on the per-call Python right-hand side of shimmy.model.reference_model,
  median of N runs in the same process;
* their ratio, and the relative difference of the steady amplitudes (max |psi| and
  max |l_g delta| over the last 20 s);
* hopf_points over V in [1, 500] m/s at Fz = 150 kN: median of N runs;
* rhs and jacobian evaluated at once on 10 000 state columns.

Targets: simulate <= 0.3 s and >= 5x faster than the reference, amplitudes agreeing to
0.5 %, Hopf points <= 20 ms.

    python benchmarks/bench_core.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.integrate import solve_ivp

from shimmy import simulate
from shimmy.model.configurations import ALL_CONFIGURATIONS
from shimmy.model.equations import build_model, jacobian, rhs
from shimmy.model.reference_model import make_rhs
from shimmy.analyses.core.response import peak_amplitude
from shimmy.analyses.core.stability import hopf_points

V_A, FZ_A, T_END, WINDOW = 30.0, 150_000.0, 60.0, 20.0
N_COLUMNS = 10_000


def _median_time(fn, repeats: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


def _reference(config) -> dict[str, float]:
    n = config.n_states
    x0 = np.zeros(n)
    x0[0] = 0.001
    sol = solve_ivp(make_rhs(config, V_A, FZ_A), (0.0, T_END), x0, method="LSODA",
                    rtol=1e-8, atol=1e-10, max_step=0.005, dense_output=True)
    t = np.arange(T_END - WINDOW, T_END + 1e-9, 0.001)
    y = sol.sol(t)
    return {"psi": peak_amplitude(y[0]), "lateral": 2.5 * peak_amplitude(y[2]), "ok": sol.success}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()

    print(f"60 s time history at point A (V={V_A:g} m/s, Fz={FZ_A / 1e3:g} kN); "
          f"medians of {args.repeats} runs")
    header = (f"{'config':<8}{'first call s':>13}{'shimmy s':>10}{'LSODA ref s':>13}{'speed-up':>10}"
              f"{'d psi amp':>11}{'d lat amp':>11}{'hopf ms':>9}")
    print(header)
    print("-" * len(header))
    for config in ALL_CONFIGURATIONS:
        start = time.perf_counter()
        simulate(config, V_A, FZ_A, t_end=T_END)
        first = time.perf_counter() - start
        t_fast, fast = _median_time(lambda: simulate(config, V_A, FZ_A, t_end=T_END), args.repeats)
        t_ref, ref = _median_time(lambda: _reference(config), args.repeats)
        t_hopf, _ = _median_time(lambda: hopf_points(config, FZ_A), args.repeats)
        d_psi = fast.amplitude["psi"] / ref["psi"] - 1.0
        d_lat = fast.amplitude["lateral"] / ref["lateral"] - 1.0
        print(f"{config.value:<8}{first:>13.3f}{t_fast:>10.3f}{t_ref:>13.3f}{t_ref / t_fast:>9.1f}x"
              f"{d_psi:>+11.2e}{d_lat:>+11.2e}{t_hopf * 1e3:>9.1f}")

    print()
    print(f"vectorised right-hand side and Jacobian on {N_COLUMNS} state columns (medians)")
    print(f"{'config':<8}{'rhs ms':>10}{'jacobian ms':>13}{'us/column':>11}")
    rng = np.random.default_rng(0)
    for config in ALL_CONFIGURATIONS:
        model = build_model(config)
        x = rng.standard_normal((model.n_states, N_COLUMNS)) * 0.01
        V = rng.uniform(1.0, 500.0, N_COLUMNS)
        t_rhs, _ = _median_time(lambda: rhs(model, x, V, FZ_A), args.repeats)
        t_jac, _ = _median_time(lambda: jacobian(model, x, V, FZ_A), args.repeats)
        print(f"{config.value:<8}{t_rhs * 1e3:>10.2f}{t_jac * 1e3:>13.2f}{(t_rhs + t_jac) / N_COLUMNS * 1e6:>11.3f}")


if __name__ == "__main__":
    main()
