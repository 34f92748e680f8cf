"""Torsional nonlinear energy sink: restoring torque from the roller-spring geometry.

docs/model.md: four roller-spring units on a track engaged over pi/3. For a relative rotation
``a`` (rad) between the strut and the absorber,

    A     = (sqrt(3)/2)(r1 + r2),       rho = r2 + r3
    tau   = sqrt(rho^2 - (A sin a)^2),  Delta = A cos a - tau
    F     = k_s (e_p - (r1 - r3 - (1 - sqrt(3)/2)(r1 + r2)) + Delta) rho / tau
    d     = Delta sin(a) A / rho
    M(a)  = 4 F d

The bracket in F equals ``e_p + Delta(a) - Delta(0)`` (because
r1 - r3 - (1 - sqrt(3)/2)(r1 + r2) = A - rho = Delta(0)), so M(0) = 0 exactly. The
geometry is defined for |a| < pi/6 only; outside, :class:`GeometryError` is raised.

The dynamics use the Taylor cubic M ~ k1 a + k3 a^3, whose coefficients are derived
here from the geometry (series expansion at a = 0, written out in
:func:`cubic_coefficients`; the tests check it against a converged polynomial fit):

    Delta0 = A - rho,  beta = A Delta0 / (2 rho)   (Delta(a) = Delta0 + beta a^2 + O(a^4))
    k1 = 4 k_s A e_p Delta0 / rho
    k3 = (4 k_s A / rho) (e_p beta + beta Delta0 + e_p Delta0 (A^2/(2 rho^2) - 1/6))
"""

from __future__ import annotations

import math

import numpy as np
from numba.extending import register_jitable

from ..errors import GeometryError

#: Half-width of the valid relative rotation (rad): the roller leaves its track at pi/6.
VALID_ANGLE = math.pi / 6.0
N_UNITS = 4


def geometry(r1: float, r2: float, r3: float) -> tuple[float, float, float]:
    """(A, rho, Delta0) of docs/model.md: track-centre distance, r2 + r3, Delta at a = 0 (m)."""
    A = 0.5 * math.sqrt(3.0) * (r1 + r2)
    rho = r2 + r3
    return A, rho, A - rho


def _check_angle(a) -> np.ndarray:
    a = np.asarray(a, dtype=float)
    bad = ~(np.abs(a) < VALID_ANGLE)
    if np.any(bad):
        worst = a[bad].flat[0]
        raise GeometryError(
            f"a={worst!r} rad is outside the NES geometry's valid range |a| < pi/6 "
            f"({VALID_ANGLE:.6f} rad): the roller leaves its track there")
    return a


def torque_exact(a, r1: float, r2: float, r3: float, k_s: float, e_p: float):
    """Exact restoring torque M(a) in N m for relative rotation(s) ``a`` in rad."""
    return torque_core(_check_angle(a), *geometry(r1, r2, r3), k_s, e_p)


@register_jitable
def torque_core(a, A, rho, delta0, k_s, e_p):
    """M(a) from precomputed geometry; plain arithmetic so numba can inline it."""
    s = np.sin(a)
    tau = np.sqrt(rho * rho - (A * s) ** 2)
    delta = A * np.cos(a) - tau
    force = k_s * (e_p + delta - delta0) * rho / tau
    arm = delta * s * A / rho
    return N_UNITS * force * arm


def stiffness_exact(a, r1: float, r2: float, r3: float, k_s: float, e_p: float):
    """Exact tangent stiffness k_nes(a) = dM/da in N m/rad (analytic derivative)."""
    return stiffness_core(_check_angle(a), *geometry(r1, r2, r3), k_s, e_p)


@register_jitable
def stiffness_core(a, A, rho, delta0, k_s, e_p):
    """dM/da from precomputed geometry (accepts arrays, complex too)."""
    s, c = np.sin(a), np.cos(a)
    tau = np.sqrt(rho * rho - (A * s) ** 2)
    dtau = -A * A * s * c / tau
    delta = A * c - tau
    ddelta = -A * s - dtau
    # M = 4 k_s A (e_p + delta - delta0) delta s / tau
    g = (e_p + delta - delta0) * delta * s
    dg = ddelta * delta * s + (e_p + delta - delta0) * (ddelta * s + delta * c)
    return N_UNITS * k_s * A * (dg * tau - g * dtau) / (tau * tau)


def cubic_coefficients(r1: float, r2: float, r3: float, k_s: float, e_p: float) -> tuple[float, float]:
    """Taylor coefficients (k1 in N m/rad, k3 in N m/rad^3) of M(a) at a = 0."""
    A, rho, delta0 = geometry(r1, r2, r3)
    beta = A * delta0 / (2.0 * rho)
    scale = N_UNITS * k_s * A / rho
    k1 = scale * e_p * delta0
    k3 = scale * (e_p * beta + beta * delta0 + e_p * delta0 * (A * A / (2.0 * rho * rho) - 1.0 / 6.0))
    return k1, k3


def torque_cubic(a, k1: float, k3: float):
    """The cubic approximation k1 a + k3 a^3 (N m)."""
    a = np.asarray(a, dtype=float)
    return k1 * a + k3 * a ** 3


#: The cubic's stated accuracy: within this relative torque error of the exact M(a) (docs/model.md).
CUBIC_TOLERANCE = 0.01


def cubic_error(a, r1: float, r2: float, r3: float, k_s: float, e_p: float):
    """Relative error |cubic - exact| / |exact| of the cubic torque at rotation(s) ``a`` (rad, 0 < |a| < pi/6)."""
    a = np.asarray(a, dtype=float)
    exact = torque_core(a, *geometry(r1, r2, r3), k_s, e_p)
    return np.abs(torque_cubic(a, *cubic_coefficients(r1, r2, r3, k_s, e_p)) - exact) / np.abs(exact)


def cubic_range(r1: float, r2: float, r3: float, k_s: float, e_p: float,
                tolerance: float = CUBIC_TOLERANCE) -> float:
    """The largest relative rotation a0 (rad) with the cubic's torque within ``tolerance`` (relative)
    of the exact torque for every 0 < |a| <= a0; the track's end (pi/6) if it never leaves it.

    The error is scanned on 2000 angles up to 0.98 pi/6 (it grows like a^4 from a = 0, the a^5 term
    the cubic drops) and its first crossing of ``tolerance`` refined by bisection to 1e-10 rad."""
    def error(a):
        return cubic_error(a, r1, r2, r3, k_s, e_p)

    grid = np.linspace(0.0, 0.98 * VALID_ANGLE, 2001)[1:]
    over = np.flatnonzero(error(grid) > tolerance)
    if over.size == 0:
        return VALID_ANGLE
    if over[0] == 0:
        return 0.0
    low, high = float(grid[over[0] - 1]), float(grid[over[0]])
    while high - low > 1e-10:
        mid = 0.5 * (low + high)
        low, high = (mid, high) if error(mid) <= tolerance else (low, mid)
    return low
