"""Device characteristics as curves: what the devices page and the API plot.

* NES: exact restoring torque and tangent stiffness over the valid relative rotation
  (a fraction of |a| < pi/6), with the cubic fit and its relative error.
* PD: equivalent damping c*(v) per unit tangential speed, the torsional damping
  c_eq = n r^2 c*(r |dpsi|) and the torque M_pd against strut rate, for the current
  design and for each material preset (same packing, the preset's density and restitution).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...model import nes, particle_damper
from ...model.parameters import MATERIALS, Parameters, check_number


@dataclass(frozen=True)
class NESCurve:
    angle: np.ndarray  # rad
    torque_exact: np.ndarray  # N m
    torque_cubic: np.ndarray
    stiffness_exact: np.ndarray  # N m/rad
    stiffness_cubic: np.ndarray
    k1: float
    k3: float
    cubic_error_at: dict[str, float]  # largest relative torque error of the cubic for |a| <= key (rad)

    def to_dict(self) -> dict[str, Any]:
        return {"angle": self.angle.tolist(), "torque_exact": self.torque_exact.tolist(),
                "torque_cubic": self.torque_cubic.tolist(), "stiffness_exact": self.stiffness_exact.tolist(),
                "stiffness_cubic": self.stiffness_cubic.tolist(), "k1": self.k1, "k3": self.k3,
                "cubic_error_at": self.cubic_error_at}


@dataclass(frozen=True)
class PDCurve:
    material: str
    speed: np.ndarray  # tangential speed v (m/s)
    rate: np.ndarray  # strut rate dpsi = v / r (rad/s)
    damping_per_speed: np.ndarray  # c*(v), N s/m
    torsional_damping: np.ndarray  # c_eq, N m s/rad
    torque: np.ndarray  # M_pd, N m

    def to_dict(self) -> dict[str, Any]:
        return {"material": self.material, "speed": self.speed.tolist(), "rate": self.rate.tolist(),
                "damping_per_speed": self.damping_per_speed.tolist(),
                "torsional_damping": self.torsional_damping.tolist(), "torque": self.torque.tolist()}


def nes_curve(*, params: Parameters | None = None, n_points: int = 201, fraction: float = 0.98) -> NESCurve:
    """NES torque and stiffness on ``n_points`` angles spanning ``fraction`` of |a| < pi/6."""
    p = params if params is not None else Parameters()
    n_points = int(check_number("n_points", n_points, 3, 100_001, integer=True))
    fraction = check_number("fraction", fraction, 0.01, 0.999)
    a = np.linspace(-fraction, fraction, n_points) * nes.VALID_ANGLE
    geometry = (p.r1, p.r2, p.r3, p.k_s, p.e_p)
    k1, k3 = nes.cubic_coefficients(*geometry)
    errors = {}
    for limit in (0.05, 0.1, 0.2):
        probe = np.linspace(limit / 400, limit, 400)
        rel = np.abs(nes.torque_cubic(probe, k1, k3) / nes.torque_exact(probe, *geometry) - 1)
        errors[f"{limit:g}"] = float(rel.max())
    return NESCurve(a, nes.torque_exact(a, *geometry), nes.torque_cubic(a, k1, k3),
                    nes.stiffness_exact(a, *geometry), k1 + 3.0 * k3 * a * a, float(k1), float(k3), errors)


def pd_curves(*, params: Parameters | None = None, v_max: float = 2.0, n_points: int = 201) -> list[PDCurve]:
    """PD damping against tangential speed for the current design and each material preset."""
    p = params if params is not None else Parameters()
    v_max = check_number("v_max", v_max, 1e-3, 20.0, "m/s")
    n_points = int(check_number("n_points", n_points, 2, 100_001, integer=True))
    v = np.linspace(0.0, v_max, n_points)
    designs = [("design", p)] + [(name, p.with_material(name)) for name in MATERIALS]
    curves = []
    for name, design in designs:
        pd = design.pd
        rate = v / pd.r
        curves.append(PDCurve(name, v, rate, particle_damper.damping_per_speed(v, pd),
                              particle_damper.torsional_damping(rate, pd), particle_damper.torque(rate, pd)))
    return curves

