"""Annular particle damper: equivalent viscous damping of the gas-solid two-phase model.

The model (docs/model.md) gives the damping per unit tangential speed of one segment,

    c*(v) = c_c + c_f + c_k
          = (c11 + c13) v^(1/2) + (c21 + c12 + c23) v - (c31 + c33) v^(3/2) + c22 v^2 + c32 v^3,

with v = r |dpsi|, and the torsional torque M_pd = n r^2 c*(r |dpsi|) dpsi. The
coefficients c_ij come from the packing and material (see :func:`damping_coefficients`).
M_pd is C^1 at dpsi = 0 with zero slope, but not twice differentiable there
(the v^(1/2) term gives |dpsi|^(1/2) dpsi).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba.extending import register_jitable

from .parameters import PDParameters


@dataclass(frozen=True)
class DampingCoefficients:
    """The nine c_ij of the model (docs/model.md, SI units) and the series of c*(v) they add up to."""

    c11: float
    c21: float
    c31: float
    c12: float
    c22: float
    c32: float
    c13: float
    c23: float
    c33: float

    @property
    def series(self) -> tuple[float, float, float, float, float]:
        """Coefficients of v^(1/2), v, v^(3/2), v^2, v^3 in c*(v)."""
        return (self.c11 + self.c13, self.c21 + self.c12 + self.c23,
                -(self.c31 + self.c33), self.c22, self.c32)

    def to_dict(self) -> dict[str, float]:
        return dict(self.__dict__)


def damping_coefficients(pd: PDParameters) -> DampingCoefficients:
    """Evaluate the c_ij of the two-phase-flow model for one chamber (docs/model.md)."""
    d, h_c = pd.d_chamber, pd.h_chamber
    a_p, rho_p, g_p, e_r, d_p, f = pd.a_p, pd.rho_p, pd.g_p, pd.e_r, pd.d_p, pd.f
    rho_m = pd.rho_m_frac * rho_p
    cbar = (9.0 / 16.0) * math.pi ** 3 * d * d * h_c * rho_m
    alpha0 = 0.2 * math.sqrt(6.0 * (1.0 - e_r) * a_p * a_p * g_p * rho_p * d_p
                             / (math.pi * d * d * rho_m))
    alpha1 = ((a_p * rho_p + rho_p * (1.0 + e_r) * a_p * a_p * g_p) * math.sin(pd.phi_f)
              / (12.0 * math.pi * d * d * rho_m * math.sqrt(pd.I2D)))
    age = a_p * g_p * (1.0 + e_r)
    alpha3 = (math.sqrt(6.0 * math.pi) * rho_p * d_p * (25.0 + 40.0 * age + 64.0 * age * age)
              / (1440.0 * math.pi * d * d * rho_m * age))
    K = 3.0 * rho_m * h_c * d * d * math.pi ** 3 / 4.0
    return DampingCoefficients(
        c11=4.0 * cbar * math.sqrt(alpha0) * math.sqrt(f),
        c21=4.0 * cbar,
        c31=4.0 * cbar * alpha0 ** 1.5 / math.sqrt(f),
        c12=4.0 * cbar * math.sqrt(alpha1) / math.sqrt(f),
        c22=4.0 * cbar * alpha1,
        c32=4.0 * cbar * alpha1 ** 1.5 / math.sqrt(f),
        c13=K * math.sqrt(alpha3) * math.sqrt(f),
        c23=K * alpha3,
        c33=(K / 4.0) * alpha3 ** 1.5 / math.sqrt(f),
    )


def damping_per_speed(v, pd: PDParameters):
    """c*(v) in N s/m for tangential speed(s) v >= 0 (m/s)."""
    v = np.asarray(v, dtype=float)
    if np.any(v < 0) or not np.all(np.isfinite(v)):
        raise ValueError("tangential speed v must be finite and >= 0 m/s")
    return series_value(v, *damping_coefficients(pd).series)


@register_jitable
def series_value(v, s12, s1, s32, s2, s3):
    """c*(v) from its series coefficients; plain arithmetic so numba can inline it."""
    root = np.sqrt(v)
    return s12 * root + s1 * v + s32 * v * root + s2 * v * v + s3 * v * v * v


def torsional_damping(dpsi, pd: PDParameters):
    """c_eq = n r^2 c*(r |dpsi|) in N m s/rad for strut rate(s) dpsi (rad/s)."""
    dpsi = np.asarray(dpsi, dtype=float)
    return pd.n * pd.r ** 2 * damping_per_speed(pd.r * np.abs(dpsi), pd)


def torque(dpsi, pd: PDParameters):
    """M_pd = c_eq(dpsi) dpsi in N m."""
    return torsional_damping(dpsi, pd) * np.asarray(dpsi, dtype=float)
