"""Compiled Dormand-Prince 5(4) integrator for the shimmy equations.

Why a compiled integrator: a 60 s history needs tens of thousands of steps, and a
Python-level right-hand side costs more per call than the whole compiled step. The
equations are not duplicated: :func:`shimmy.model.equations.vector_field` is plain
arithmetic that numba inlines here.

Method: explicit embedded Runge-Kutta 5(4) of Dormand and Prince (Hairer, Norsett &
Wanner, Solving ODEs I, Table 5.2), FSAL, local extrapolation, error measured in the
RMS norm of err_i / (atol + rtol max(|y_i|, |y_new,i|)), step factor
0.9 err^(-1/5) bounded to [0.2, 5]. Output at a uniform grid by cubic Hermite
interpolation between accepted steps (its error is O(h^4), far below the step error
at the tolerances used). The model is not stiff over V <= 500 m/s (fastest decay
V/L <= 1667 1/s), so an explicit method is efficient.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .equations import vector_field

N_FULL = 7

# Integration status codes, returned to :mod:`shimmy.analyses.core.simulation`.
SUCCESS = 0
MAX_STEPS = 1
NES_OUT_OF_RANGE = 2
NOT_FINITE = 3
STEP_TOO_SMALL = 4

# Dormand-Prince tableau.
C2, C3, C4, C5 = 1 / 5, 3 / 10, 4 / 5, 8 / 9
A21 = 1 / 5
A31, A32 = 3 / 40, 9 / 40
A41, A42, A43 = 44 / 45, -56 / 15, 32 / 9
A51, A52, A53, A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
A61, A62, A63, A64, A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
B1, B3, B4, B5, B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
E1, E3, E4, E5, E6, E7 = (71 / 57600, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40)


@njit(cache=True)
def _f(y, out, V, Fz, c, has_nes, has_pd, exact_nes):
    d = vector_field(y[0], y[1], y[2], y[3], y[4], y[5], y[6], V, Fz, c, has_nes, has_pd, exact_nes)
    for i in range(N_FULL):
        out[i] = d[i]


@njit(cache=True)
def integrate(x0, t_end, dt_out, V, Fz, c, has_nes, has_pd, exact_nes, rtol, atol, max_steps, out):
    """Integrate from t = 0 at constant (V, Fz) and write the state at t = k dt_out into ``out[k]``.

    Returns (status, accepted steps, rejected steps, right-hand-side calls, samples written).
    """
    table_t = np.zeros(1)
    table_v = np.full(1, V)
    table_fz = np.full(1, Fz)
    return integrate_profile(x0, t_end, dt_out, table_t, table_v, table_fz, c, has_nes, has_pd, exact_nes,
                             rtol, atol, max_steps, out)


@njit(cache=True)
def integrate_profile(x0, t_end, dt_out, table_t, table_v, table_fz, c, has_nes, has_pd, exact_nes, rtol, atol,
                      max_steps, out):
    """Integrate from t = 0 with V(t) and Fz(t) interpolated linearly in the table (table_t[0] = 0,
    increasing; the last segment extends past its end) and write the state at t = k dt_out into ``out[k]``.

    No step crosses an interior point of the table (a kink of V or Fz would cost rejected steps
    and accuracy): a step that would reach it, or land within 1 % of a step short of it, ends on it.
    A one-row table is a constant (V, Fz), stepped exactly as :func:`integrate` would.
    Returns (status, accepted steps, rejected steps, right-hand-side calls, samples written).
    """
    n_out = out.shape[0]
    n_table = table_t.shape[0]
    slope_v = np.zeros(n_table)
    slope_fz = np.zeros(n_table)
    for j in range(n_table - 1):
        slope_v[j] = (table_v[j + 1] - table_v[j]) / (table_t[j + 1] - table_t[j])
        slope_fz[j] = (table_fz[j + 1] - table_fz[j]) / (table_t[j + 1] - table_t[j])
    if n_table > 1:  # the last segment's slope holds past the end of the table
        slope_v[n_table - 1] = slope_v[n_table - 2]
        slope_fz[n_table - 1] = slope_fz[n_table - 2]
    seg = 0
    last_seg = max(0, n_table - 2)  # segments 0..last_seg; points 1..n_table-2 are interior
    y = x0.copy()
    k1 = np.empty(N_FULL)
    k2 = np.empty(N_FULL)
    k3 = np.empty(N_FULL)
    k4 = np.empty(N_FULL)
    k5 = np.empty(N_FULL)
    k6 = np.empty(N_FULL)
    k7 = np.empty(N_FULL)
    tmp = np.empty(N_FULL)
    y_new = np.empty(N_FULL)
    t0, v0, f0, sv, sf = table_t[0], table_v[0], table_fz[0], slope_v[0], slope_fz[0]
    _f(y, k1, v0, f0, c, has_nes, has_pd, exact_nes)
    n_calls = 1
    out[0, :] = y
    written = 1
    t = 0.0
    # Initial step from the size of the derivative (Hairer's simple heuristic).
    d0 = 0.0
    d1 = 0.0
    for i in range(N_FULL):
        sc = atol + rtol * abs(y[i])
        d0 += (y[i] / sc) ** 2
        d1 += (k1[i] / sc) ** 2
    d0 = np.sqrt(d0 / N_FULL)
    d1 = np.sqrt(d1 / N_FULL)
    h = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h = min(h, dt_out)
    accepted = 0
    rejected = 0
    while written < n_out:
        if accepted + rejected >= max_steps:
            return MAX_STEPS, accepted, rejected, n_calls, written
        if h < 1e-14 * max(1.0, t):
            return STEP_TOO_SMALL, accepted, rejected, n_calls, written
        # a table point closer than rounding to t is passed (a step to it could not be taken)
        while seg < last_seg and table_t[seg + 1] - t <= 1e-12 * max(1.0, abs(t)):
            seg += 1
        t0, v0, f0, sv, sf = table_t[seg], table_v[seg], table_fz[seg], slope_v[seg], slope_fz[seg]
        h_free = h
        to_kink = False
        if seg < last_seg and t + 1.01 * h >= table_t[seg + 1]:
            h = table_t[seg + 1] - t
            to_kink = True
        for i in range(N_FULL):
            tmp[i] = y[i] + h * A21 * k1[i]
        ts = t + C2 * h - t0
        _f(tmp, k2, v0 + ts * sv, f0 + ts * sf, c, has_nes, has_pd, exact_nes)
        for i in range(N_FULL):
            tmp[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i])
        ts = t + C3 * h - t0
        _f(tmp, k3, v0 + ts * sv, f0 + ts * sf, c, has_nes, has_pd, exact_nes)
        for i in range(N_FULL):
            tmp[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i])
        ts = t + C4 * h - t0
        _f(tmp, k4, v0 + ts * sv, f0 + ts * sf, c, has_nes, has_pd, exact_nes)
        for i in range(N_FULL):
            tmp[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i])
        ts = t + C5 * h - t0
        _f(tmp, k5, v0 + ts * sv, f0 + ts * sf, c, has_nes, has_pd, exact_nes)
        for i in range(N_FULL):
            tmp[i] = y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i])
        t_new = table_t[seg + 1] if to_kink else t + h
        ts = t_new - t0
        v1, f1 = v0 + ts * sv, f0 + ts * sf
        _f(tmp, k6, v1, f1, c, has_nes, has_pd, exact_nes)
        for i in range(N_FULL):
            y_new[i] = y[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i])
        _f(y_new, k7, v1, f1, c, has_nes, has_pd, exact_nes)
        n_calls += 6
        err = 0.0
        finite = True
        for i in range(N_FULL):
            e = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i])
            sc = atol + rtol * max(abs(y[i]), abs(y_new[i]))
            err += (e / sc) ** 2
            if not np.isfinite(y_new[i]):
                finite = False
        err = np.sqrt(err / N_FULL)
        if not finite or not np.isfinite(err):
            if h < 1e-10:
                return NOT_FINITE, accepted, rejected, n_calls, written
            h *= 0.2
            rejected += 1
            continue
        if err <= 1.0:
            # Dense output on the uniform grid inside (t, t_new].
            while written < n_out and written * dt_out <= t_new:
                s = (written * dt_out - t) / h
                h00 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
                h10 = s * (1.0 - s) ** 2
                h01 = s * s * (3.0 - 2.0 * s)
                h11 = s * s * (s - 1.0)
                for i in range(N_FULL):
                    out[written, i] = (h00 * y[i] + h10 * h * k1[i] + h01 * y_new[i] + h11 * h * k7[i])
                written += 1
            t = t_new
            for i in range(N_FULL):
                y[i] = y_new[i]
                k1[i] = k7[i]
            accepted += 1
            if has_nes and exact_nes and abs(y[0] - y[5]) >= np.pi / 6:
                return NES_OUT_OF_RANGE, accepted, rejected, n_calls, written
            if err == 0.0:
                factor = 5.0
            else:
                factor = min(5.0, max(0.2, 0.9 * err ** -0.2))
            if to_kink:
                seg += 1
                # the step was cut short to end on the kink: the step before the cut is still a good guess
                h = max(h * factor, min(h_free, h * 5.0))
            else:
                h *= factor
        else:
            h *= max(0.2, 0.9 * err ** -0.2)
            rejected += 1
    return SUCCESS, accepted, rejected, n_calls, written
