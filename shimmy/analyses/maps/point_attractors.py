"""The gear's attractors at one operating point, and which of them a run from a disturbed start ends on.

* **Attractors** (:func:`point_attractors`): the stable equilibrium and stable limit cycles of the
  one-parameter bifurcation diagram in V at the load, at the point's speed (the map's reading,
  :func:`~shimmy.analyses.maps.map_slices.attractors_at`), and the diagram's unstable cycles at
  that speed (the saddle cycles between the basins). Then runs from the standard start
  (psi = 0.001 rad), a large yaw angle (0.2 rad) and a large lateral deflection (l_g delta = 0.1 m),
  the diagram's own large starts: each run's end is matched to the attractors; a settled end that
  matches none (a motion the diagram has not got, such as a quasi-periodic one past a torus point)
  is added as an attractor found by simulation. The standard start's attractor is marked.
* **Where a run ends** (:class:`AttractorSet`): the run's amplitudes over a window, as the vector
  e = (sqrt(k_psi) psi_amp, sqrt(k_delta) delta_amp) (the elastic energies' square roots, which
  put torsion and bending on one scale), against each attractor's: a cycle is matched when
  |e - e_k| <= ``MATCH_TOL`` (10 %) of |e_k| and e is nearer to it than to every saddle cycle; the
  equilibrium when |e| is below ``EQUILIBRIUM_FRACTION`` (5 %) of the smallest cycle's (0.01 rad of
  torsion if there is no cycle) and falling.
* **Runs** (:class:`RunUnit`, through the executor): the compiled integrator (as
  :func:`~shimmy.analyses.core.simulation.simulate`, same tolerances), in windows of ``WINDOW``
  (1 s, more than six periods of the slowest shimmy mode); a run stops early when two windows in a
  row are matched to the same attractor. A run that gets to ``t_max`` is judged on its last
  ``FULL_WINDOW`` (20 s; amplitudes the largest over it, falling or settled against the 20 s
  before, as a time history's steady state is): matched, or ``UNSETTLED``; where straight rolling
  is the only attractor and there is no saddle cycle, a run still falling by more than 1 % against
  the 20 s before ends on it (a slow decay, as a time history's response type ``Stable``); a failed
  integration is ``FAILED``. A *full* run (the checks of a threshold) never stops early.
* **The disturbance's size** (:class:`EnergyNorm`): the energy of the linearised gear at straight
  rolling, E = (1/2)(I_psi dpsi^2 + k_psi' psi^2 + I_x ddelta^2 + k_delta delta^2), with I_psi =
  I_z (+ I_pd with the particle damper) and k_psi' = k_psi (+ k_1 with the NES, whose absorber is at
  rest); as a size, the yaw angle of the same energy, a = sqrt(2 E / k_psi'): a yaw kick psi0 has
  size psi0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ...model import integrator
from ...model.configurations import Configuration
from ...model.equations import build_model
from ...model.units import mm
from ...model.nes import cubic_coefficients
from ...model.parameters import Parameters
from ..core.basins import FAILED, UNSETTLED
from .margin_options import COMPONENTS
from ..core.response import mode_of, peak_amplitude, torsional_share

MATCH_TOL = 0.1
EQUILIBRIUM_FRACTION = 0.05
EQUILIBRIUM_REFERENCE_PSI = 0.01  # rad: the scale of "small" where there is no cycle
WINDOW = 1.0  # s
FULL_WINDOW = 20.0  # s
DECAY_RATIO = 0.99  # a run falling by more than 1 % per window decays (as a time history's response type)
STEADY_CHANGE = 0.01  # a full run is settled when its amplitude changed by less than this between windows
DT_OUT = 0.001  # s
#: Discovery starts: (what, size): psi in rad, the lateral deflection l_g delta in m.
DISCOVERY_STARTS = (("standard start", "psi", 0.001), ("large yaw", "psi", 0.2), ("large lateral", "lateral", 0.1))
TRIVIAL_PSI = 1e-6  # rad: cycles smaller than this are the zero-amplitude ends of branches


@dataclass(frozen=True)
class EnergyNorm:
    """Weights c of E = (1/2) sum c_i x_i^2 over psi, dpsi, delta, ddelta (J), and k_psi' = c_psi."""

    weights: tuple[float, float, float, float]

    @classmethod
    def of(cls, config: Configuration, params: Parameters) -> "EnergyNorm":
        g = params.gear
        k_psi = g.k_psi + (cubic_coefficients(params.nes.r1, params.nes.r2, params.nes.r3, params.nes.k_s,
                                              params.nes.e_p)[0] if config.has_nes else 0.0)
        inertia = g.Iz + (params.pd.I_pd if config.has_pd else 0.0)
        return cls((float(k_psi), float(inertia), float(g.k_delta), float(g.Ix)))

    @property
    def k_psi(self) -> float:
        return self.weights[0]

    def scales(self, names: Sequence[str]) -> np.ndarray:
        """State change per unit of size (equivalent yaw angle) along each named component: sqrt(k_psi' / c_i)."""
        return np.array([math.sqrt(self.k_psi / self.weights[COMPONENTS[n][0]]) for n in names])

    def energy(self, size: float) -> float:
        """The energy (J) of a disturbance of ``size`` (equivalent yaw angle, rad)."""
        return 0.5 * self.k_psi * size * size

    def to_dict(self) -> dict[str, Any]:
        return {"energy": "E = (1/2)(k_psi' psi^2 + I_psi dpsi^2 + k_delta delta^2 + I_x ddelta^2)",
                "size": "a = sqrt(2 E / k_psi'), the yaw angle of the same energy (rad)",
                "weights": dict(zip(COMPONENTS, self.weights, strict=True)),
                "units": {"psi": "N m/rad", "dpsi": "kg m^2", "delta": "N m/rad", "ddelta": "kg m^2"}}


@dataclass(frozen=True)
class AttractorSet:
    """The attractors and saddle cycles at a point as energy-amplitude vectors, and the rule that says where
    a run ends (module docstring). ``attractors``: one (psi_amp, delta_amp) per attractor, (0, 0) for the
    equilibrium; ``saddles``: those of the unstable cycles."""

    attractors: tuple[tuple[float, float], ...]
    equilibrium: tuple[bool, ...]
    saddles: tuple[tuple[float, float], ...]
    k_psi: float
    k_delta: float

    def vector(self, psi_amp: float, delta_amp: float) -> np.ndarray:
        return np.array([math.sqrt(self.k_psi) * psi_amp, math.sqrt(self.k_delta) * delta_amp])

    def small(self) -> float:
        """|e| below which a falling run is on x = 0."""
        sizes = [float(np.linalg.norm(self.vector(*a))) for a, eq in zip(self.attractors, self.equilibrium,
                                                                          strict=True) if not eq]
        sizes += [float(np.linalg.norm(self.vector(*s))) for s in self.saddles]
        base = min(sizes) if sizes else math.sqrt(self.k_psi) * EQUILIBRIUM_REFERENCE_PSI
        return EQUILIBRIUM_FRACTION * base

    def decaying(self) -> int:
        """The equilibrium's index where it is the only attractor and there is no saddle cycle (a run still
        falling at the end goes there), else UNSETTLED."""
        if self.saddles or len(self.attractors) != 1 or not self.equilibrium[0]:
            return UNSETTLED
        return 0

    def label(self, psi_amp: float, delta_amp: float, falling: bool) -> int:
        """The attractor the amplitudes match, or UNSETTLED."""
        e = self.vector(psi_amp, delta_amp)
        size = float(np.linalg.norm(e))
        best, distance = UNSETTLED, math.inf
        for k, (a, eq) in enumerate(zip(self.attractors, self.equilibrium, strict=True)):
            if eq:
                if falling and size <= self.small():
                    return k
                continue
            target = self.vector(*a)
            d = float(np.linalg.norm(e - target))
            if d <= MATCH_TOL * float(np.linalg.norm(target)) and d < distance:
                best, distance = k, d
        if best >= 0 and any(float(np.linalg.norm(e - self.vector(*s))) <= distance for s in self.saddles):
            return UNSETTLED  # lingering near a saddle cycle
        return best


@dataclass(frozen=True)
class RunUnit:
    """Runs from several starts at one point (a small frozen unit for the executor): each ends as
    (label, psi_amp (rad), delta_amp (rad), t (s), settled)."""

    config: Configuration
    V: float
    Fz: float
    params: Parameters
    starts: tuple[tuple[float, ...], ...]
    attractors: AttractorSet
    t_max: float
    full: bool = False

    def run(self) -> list[tuple[int, float, float, float, bool]]:
        model = build_model(self.config, self.params)
        return [run_to_attractor(model, np.array(x0), self.V, self.Fz, self.attractors, self.t_max, self.full)
                for x0 in self.starts]

    def describe(self) -> str:
        return f"{len(self.starts)} run{'s' if len(self.starts) > 1 else ''} at V = {self.V:g} m/s"


def run_to_attractor(model, x0: np.ndarray, V: float, Fz: float, attractors: AttractorSet, t_max: float,
                     full: bool = False) -> tuple[int, float, float, float, bool]:
    """(label, psi_amp, delta_amp, t, settled) of the run from ``x0`` (module docstring)."""
    start = np.zeros(integrator.N_FULL)
    start[:x0.size] = x0
    samples = int(round(WINDOW / DT_OUT)) + 1
    out = np.empty((samples, integrator.N_FULL))
    windows = int(math.ceil(t_max / WINDOW - 1e-9))
    psi, delta = np.zeros(windows), np.zeros(windows)
    previous, streak = UNSETTLED, 0
    for w in range(windows):
        status, _, _, _, written = integrator.integrate(start, WINDOW, DT_OUT, V, Fz, model.coefficients, *model.flags,
                                                        1e-7, 1e-10, 10_000_000, out)
        if status != integrator.SUCCESS:
            return FAILED, math.nan, math.nan, w * WINDOW, False
        start = out[written - 1].copy()
        psi[w], delta[w] = peak_amplitude(out[:written, 0]), peak_amplitude(out[:written, 2])
        if full:
            continue
        size = float(np.linalg.norm(attractors.vector(psi[w], delta[w])))
        falling = w > 0 and size < float(np.linalg.norm(attractors.vector(psi[w - 1], delta[w - 1])))
        here = attractors.label(psi[w], delta[w], falling)
        streak = streak + 1 if here >= 0 and here == previous else (1 if here >= 0 else 0)
        previous = here
        if streak >= 2:
            return here, float(psi[w]), float(delta[w]), (w + 1) * WINDOW, True
    span = max(1, min(int(round(FULL_WINDOW / WINDOW)), windows // 2))
    last = (psi[-span:].max(), delta[-span:].max())
    before = (psi[-2 * span:-span].max(), delta[-2 * span:-span].max()) if windows >= 2 * span else last
    size = float(np.linalg.norm(attractors.vector(*last)))
    size_before = float(np.linalg.norm(attractors.vector(*before)))
    settled = size_before > 0 and abs(size / size_before - 1.0) < STEADY_CHANGE
    label = attractors.label(last[0], last[1], size < size_before)
    if label < 0 and size < DECAY_RATIO * size_before:
        label = attractors.decaying()  # still falling, with nothing else to go to: the time history's Stable
    return label, float(last[0]), float(last[1]), windows * WINDOW, bool(settled or label >= 0)


#: The orbit a disturbance is added to is settled when its energy amplitude changes by less than this between
#: two windows.
ORBIT_SETTLED = 1e-3


@dataclass(frozen=True)
class OrbitUnit:
    """The states at ``count`` phases of the attractor ``label`` that the run from ``start`` settles on (a small
    frozen unit for the executor): :func:`orbit_states`."""

    config: Configuration
    V: float
    Fz: float
    params: Parameters
    start: tuple[float, ...]
    attractors: AttractorSet
    label: int
    t_max: float
    count: int

    def run(self) -> dict[str, Any]:
        return orbit_states(build_model(self.config, self.params), np.array(self.start), self.V, self.Fz,
                            self.attractors, self.label, self.t_max, self.count)

    def describe(self) -> str:
        return f"the orbit the standard start reaches at V = {self.V:g} m/s"


def _maxima(psi: np.ndarray) -> np.ndarray:
    """The samples where psi has a positive local maximum."""
    inner = (psi[1:-1] > psi[:-2]) & (psi[1:-1] >= psi[2:]) & (psi[1:-1] > 0.0)
    return np.flatnonzero(inner) + 1


def orbit_states(model, x0: np.ndarray, V: float, Fz: float, attractors: AttractorSet, label: int, t_max: float,
                 count: int) -> dict[str, Any]:
    """The run from ``x0``, in windows of ``WINDOW``, until it is matched to attractor ``label`` in two windows in
    a row and its energy amplitude changed by less than ``ORBIT_SETTLED`` between them (at most ``t_max``); then,
    from the state at the last maximum of the yaw angle psi in that window (phase 0, to the 1 ms of the
    samples), the states at ``count`` equal steps over one yaw period (the mean spacing of the window's psi
    maxima; the window's length if it has fewer than two). Returns {"states": count x N_FULL rows or None,
    "period" (s), "t_s": the time settled, "settled", "status": why there are no states}."""
    start = np.zeros(integrator.N_FULL)
    start[:x0.size] = x0
    samples = int(round(WINDOW / DT_OUT)) + 1
    out = np.empty((samples, integrator.N_FULL))
    windows = int(math.ceil(t_max / WINDOW - 1e-9))
    previous_size, streak, settled = None, 0, False
    written = 0
    for w in range(windows):
        status, _, _, _, written = integrator.integrate(start, WINDOW, DT_OUT, V, Fz, model.coefficients, *model.flags,
                                                        1e-7, 1e-10, 10_000_000, out)
        if status != integrator.SUCCESS:
            return {"states": None, "period": None, "t_s": w * WINDOW, "settled": False,
                    "status": "the integration failed"}
        start = out[written - 1].copy()
        psi, delta = peak_amplitude(out[:written, 0]), peak_amplitude(out[:written, 2])
        size = float(np.linalg.norm(attractors.vector(psi, delta)))
        here = attractors.label(psi, delta, previous_size is not None and size < previous_size)
        streak = streak + 1 if here == label else 0
        change = math.inf if not previous_size else abs(size / previous_size - 1.0)
        previous_size = size
        if streak >= 2 and change < ORBIT_SETTLED:
            settled = True
            break
    if streak < 2:
        return {"states": None, "period": None, "t_s": windows * WINDOW, "settled": False,
                "status": f"the run is not on attractor {label} at {windows * WINDOW:g} s"}
    t_settled = (w + 1) * WINDOW
    peaks = _maxima(out[:written, 0])
    period = float(np.mean(np.diff(peaks))) * DT_OUT if peaks.size >= 2 else WINDOW
    phase0 = out[peaks[-1]].copy() if peaks.size else out[written - 1].copy()
    rows = np.empty((count + 1, integrator.N_FULL))
    status, _, _, _, got = integrator.integrate(phase0, period, period / count, V, Fz, model.coefficients,
                                                *model.flags, 1e-7, 1e-10, 10_000_000, rows)
    if status != integrator.SUCCESS or got < count:
        return {"states": None, "period": period, "t_s": t_settled, "settled": settled,
                "status": "the integration over one period failed"}
    return {"states": rows[:count].copy(), "period": period, "t_s": t_settled, "settled": settled, "status": "ok"}


def cycles_at(diagram, V: float) -> list[dict[str, Any]]:
    """Every cycle of the diagram's periodic branches at speed V, stable or not (linear between the drawn
    points, as :func:`~shimmy.analyses.maps.map_slices.attractors_on` reads them), except the
    zero-amplitude ends of branches."""
    found = []
    for k, b in enumerate(diagram.branches):
        if b.kind != "periodic" or b.V.size < 2:
            continue
        first = np.arange(b.V.size - 1)
        if b.closed:
            first = np.append(first, b.V.size - 1)
        for i in first:
            j = (i + 1) % b.V.size
            lo, hi = sorted((b.V[i], b.V[j]))
            if not lo <= V <= hi or lo == hi:
                continue
            f = (V - b.V[i]) / (b.V[j] - b.V[i])
            near = i if f <= 0.5 else j
            psi = float(b.max_psi[i] + f * (b.max_psi[j] - b.max_psi[i]))
            lateral = float(b.max_lateral[i] + f * (b.max_lateral[j] - b.max_lateral[i]))
            if psi <= TRIVIAL_PSI:
                continue
            stable = bool(b.stable[i]) if b.stable[i] == b.stable[j] else bool(b.stable[near])
            found.append({"branch": k, "stable": stable, "mode": b.mode[near] or b.mode[i] or b.mode[j],
                          "psi": psi, "lateral": lateral,
                          "period": float(b.period[i] + f * (b.period[j] - b.period[i]))})
    return found


@dataclass(frozen=True)
class PointAttractors:
    """The attractors at a point (each a dict: kind, mode, amplitude, period, source, standard_start), the
    saddle cycles (dicts: mode, amplitude, period, branch), whether straight rolling is stable, the
    classifier, the norm, the warnings and the number of runs made."""

    attractors: list[dict[str, Any]]
    saddles: list[dict[str, Any]]
    straight_rolling_stable: bool
    classifier: AttractorSet
    norm: EnergyNorm
    warnings: list[str]
    runs: int

    @property
    def standard(self) -> int | None:
        """The index of the attractor the standard start reaches (None if it reached none)."""
        return next((k for k, a in enumerate(self.attractors) if a["standard_start"]), None)


def _amplitude(psi: float, lateral: float, l_g: float) -> dict[str, float]:
    return {"psi": psi, "delta": lateral / l_g, "lateral": lateral}


def point_attractors(config: Configuration, V: float, Fz: float, *, params: Parameters, diagram, run_units,
                     t_max: float) -> PointAttractors:
    """The attractors at (V, Fz) from ``diagram`` (the one-parameter diagram in V at Fz) and the discovery runs
    (module docstring), run through ``run_units(units) -> [each unit's results]`` (side by side on an executor)."""
    from .map_slices import attractors_at

    l_g, k_psi, k_delta = params.gear.l_g, params.gear.k_psi, params.gear.k_delta
    found = attractors_at(diagram, V)
    attractors = []
    for a in found:
        equilibrium = a["kind"] == "equilibrium"
        attractors.append({"kind": a["kind"], "mode": "equilibrium" if equilibrium else str(a["mode"]),
                           "amplitude": _amplitude(a["max_psi"], a["max_lateral"], l_g), "period": a["period"],
                           "source": "diagram" if equilibrium else f"diagram, branch {a['branch']}",
                           "standard_start": False})
    saddles = [{"mode": str(c["mode"]), "amplitude": _amplitude(c["psi"], c["lateral"], l_g), "period": c["period"],
                "branch": c["branch"]} for c in cycles_at(diagram, V) if not c["stable"]]
    straight = any(a["kind"] == "equilibrium" for a in attractors)
    warnings: list[str] = []

    def classifier() -> AttractorSet:
        return AttractorSet(tuple((a["amplitude"]["psi"], a["amplitude"]["delta"]) for a in attractors),
                            tuple(a["kind"] == "equilibrium" for a in attractors),
                            tuple((s["amplitude"]["psi"], s["amplitude"]["delta"]) for s in saddles), k_psi, k_delta)

    n = config.n_states
    starts = []
    for _, what, size in DISCOVERY_STARTS:
        x0 = np.zeros(n)
        x0[0 if what == "psi" else 2] = size if what == "psi" else size / l_g
        starts.append(tuple(x0))
    units = [RunUnit(config, V, Fz, params, (x0,), classifier(), t_max) for x0 in starts]
    ends = [r[0] for r in run_units(units)]
    for (name, _, _), (label, psi, delta, _, settled) in zip(DISCOVERY_STARTS, ends, strict=True):
        if label == FAILED:
            warnings.append(f"the run from the {name} failed (the integration stopped)")
            continue
        if label < 0 and settled:
            current = classifier()
            label = current.label(psi, delta, False)  # an attractor added by an earlier discovery run
            if label < 0:
                share = float(torsional_share(psi, delta, k_psi, k_delta))
                attractors.append({"kind": "simulation", "mode": str(mode_of(share)),
                                   "amplitude": _amplitude(psi, l_g * delta, l_g), "period": None,
                                   "source": f"simulation from the {name}", "standard_start": False})
                label = len(attractors) - 1
                warnings.append(f"the run from the {name} settles on a motion the diagram does not have at "
                                f"V = {V:g} m/s (psi {psi:.4g} rad, l_g delta {mm(l_g * delta, 4)}): added as an "
                                "attractor")
        elif label < 0:
            warnings.append(f"the run from the {name} settles on none of the attractors within {t_max:g} s")
        if name == "standard start" and label >= 0:
            attractors[label]["standard_start"] = True
    if not attractors:
        warnings.append("no attractor found at this point")
    return PointAttractors(attractors, saddles, straight, classifier(), EnergyNorm.of(config, params), warnings,
                           len(units))
