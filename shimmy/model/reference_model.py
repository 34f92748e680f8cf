"""A plain, per-call Python right-hand side written line by line from the equations of docs/model.md.

It shares no code with :mod:`shimmy.model.equations` beyond the parameter set and the
device coefficient formulas, so it serves two purposes: the tests check the
vectorised/compiled equations against it, and the benchmark uses it with scipy's
LSODA as the straightforward baseline the compiled integrator is measured against.
"""

from __future__ import annotations

import math

from .configurations import Configuration
from .nes import cubic_coefficients
from .parameters import Parameters
from .particle_damper import damping_coefficients


def make_rhs(config: Configuration | str, V: float, Fz: float, params: Parameters | None = None):
    """Return ``f(t, x) -> list`` for scipy's ``solve_ivp`` at one operating point."""
    config = Configuration.parse(config)
    p = params if params is not None else Parameters()
    g = p.gear
    Iz = g.Iz + (p.pd.I_pd if config.has_pd else 0.0)
    e_eff = g.e * math.cos(g.phi) + (g.R + g.e * math.sin(g.phi)) * math.tan(g.phi)
    k1, k3 = cubic_coefficients(p.r1, p.r2, p.r3, p.k_s, p.e_p)
    cc = damping_coefficients(p.pd)
    n_r2, r = p.pd.n * p.pd.r ** 2, p.pd.r
    has_nes, has_pd = config.has_nes, config.has_pd

    def c_star(v: float) -> float:
        c_c = cc.c11 * v ** 0.5 + cc.c21 * v - cc.c31 * v ** 1.5
        c_f = cc.c12 * v + cc.c22 * v ** 2 + cc.c32 * v ** 3
        c_k = cc.c13 * v ** 0.5 + cc.c23 * v - cc.c33 * v ** 1.5
        return c_c + c_f + c_k

    def rhs(t, x):
        psi, dpsi, delta, ddelta, lam = x[0], x[1], x[2], x[3], x[4]
        theta = psi * math.cos(g.phi)
        alpha = math.atan(lam / g.L)
        w = math.atan(7.0 * math.tan(alpha))
        F_lam = g.k_lam * w * math.cos(0.95 * w) * Fz
        if abs(alpha) <= g.alpha_m:
            M_ka = g.k_a * (g.alpha_m / math.pi) * math.sin(math.pi * alpha / g.alpha_m) * Fz
        else:
            M_ka = 0.0
        M_Dlam = g.c_lam * dpsi * math.cos(g.phi) / V
        M_nes = 0.0
        out_nes = []
        if has_nes:
            psis, dpsis = x[5], x[6]
            u = psi - psis
            M_nes = p.c_nes * (dpsi - dpsis) + k1 * u + k3 * u ** 3
            out_nes = [dpsis, M_nes / p.I_nes]
        M_pd = n_r2 * c_star(r * abs(dpsi)) * dpsi if has_pd else 0.0
        psi_dd = -(g.c_psi * dpsi + g.k_psi * psi + M_ka + e_eff * F_lam + M_Dlam + M_nes + M_pd
                   - Fz * math.sin(g.phi) * e_eff * math.sin(theta)) / Iz
        delta_dd = -(g.c_delta * ddelta + g.k_delta * delta
                     + g.l_g * F_lam * math.cos(theta) * math.cos(g.phi)
                     - Fz * e_eff * math.sin(theta)) / g.Ix
        lam_d = (-(V / g.L) * lam + V * math.sin(theta) + g.l_g * ddelta * math.cos(delta)
                 + (e_eff - g.h) * math.cos(theta) * dpsi * math.cos(g.phi))
        return [dpsi, psi_dd, ddelta, delta_dd, lam_d, *out_nes]

    return rhs
