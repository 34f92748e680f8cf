"""Robustness of a design to manufacturing and tyre tolerances: quasi-Monte Carlo and linear propagation.

Each toleranced parameter theta_i = theta_i0 (1 + r_i xi_i): ``normal`` xi ~ N(0, 1) (r the relative
standard deviation), ``uniform`` xi ~ U(-1, 1) (r the relative half-width, standard deviation
r / sqrt 3). The xi come from a scrambled Sobol sequence (scipy.stats.qmc, seeded: the same seed gives
the same samples) mapped through the inverse normal distribution where needed. Samples are split
into chunks, each chunk one unit of the executor.

Per sample: the Hopf speeds at the load Fz (eigenvalue scan, :func:`shimmy.analyses.core.stability.hopf_points`),
the minimum shimmy load (the lowest point of the Hopf curves, Newton from the nominal design's point,
:func:`shimmy.analyses.decisions.sensitivity.polish_lowest_point`, or the continued curves where Newton does not
converge from there), and at each of the nine operating points
whether straight rolling is unstable there (an eigenvalue with positive real part). That is linear
shimmy; a point in a bistable region (x = 0 stable beside a stable cycle) is not counted, so
``p_shimmy`` is the probability that shimmy starts from any disturbance.

**With a disturbance** (``disturbance``: a size as the yaw angle of the same energy, rad; along
``disturbance_direction``, psi by default: a yaw kick of that angle): at each sample's nine points the
margins (:func:`shimmy.analyses.maps.margins.margins`: the attractors of the bifurcation diagram at
the point's load and of runs from large starts, the bracketing scan up to the size and bisection)
say which shimmy attractors a disturbance from straight rolling no larger than the size reaches
(the standard start's among them where x = 0 is unstable: its threshold is 0). Shimmy follows the
disturbance where x = 0 is unstable or one of them is reached, so ``p_shimmy_disturbed`` >=
``p_shimmy`` at every point (equal where no stable straight rolling coexists with a cycle); beside
it, the share of samples in which each mode (torsional, the fatigue-critical one; lateral; both) is
reached: where a torsional and a lateral cycle coexist (the map's Bistable), the linear figure says
shimmy and this one says which. The shares come with 95 % Wilson intervals (the Sobol samples are
spread more evenly than independent ones: the intervals are conservative). A basin thinner than the
scan's grid along the direction can be missed (:mod:`shimmy.analyses.core.basins`). About 5 s per
sample on one core (four diagrams and nine margins).

Linear propagation beside it: std = sqrt(sum_i (dQ/dtheta_i sigma_i)^2) with the sensitivities of
:mod:`shimmy.analyses.decisions.sensitivity` and sigma_i = theta_i0 r_i (normal) or theta_i0 r_i / sqrt 3 (uniform);
at an operating point the growth rate g = max Re lambda is propagated the same way and
P(g > 0) = Phi(g0 / sigma_g) (exact for normal tolerances to first order, the normal approximation for
uniform ones).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import scipy.linalg
from scipy.stats import norm, qmc

from ...version import __version__
from ...errors import ConvergenceError, InvalidParameterError
from ...model.configurations import OPERATING_POINTS, Configuration, affects
from ...model.equations import build_model
from ...model.parameters import DEFAULT_FZ, FZ_RANGE, PARAMETER_SPECS, Parameters, check_number, unknown_name_error
from . import spec_text
from .design_space import DISTRIBUTIONS, TOLERANCE_LIMITS
from .summaries import robustness_summary
from ..core.executors import open_executor, run_units
from .sensitivity import (V_BAND, coefficient_pairs, hopf_sensitivities, jacobian_derivatives, min_shimmy_sensitivity,
                          polish_lowest_point)
from ..core.stability import Linearisation, hopf_points

FZ_BOX = FZ_RANGE  # N: where the lowest point of the Hopf curves is looked for
CHUNK = 16  # samples per executor unit
CHUNK_DISTURBED = 2  # samples per unit with a disturbance (a diagram per load and margins per stable point)


@dataclass(frozen=True)
class Tolerance:
    name: str
    relative: float
    distribution: str = "normal"

    @classmethod
    def parse(cls, text: str) -> "Tolerance":
        """'k_lam=0.05' (normal, 5 % standard deviation) or 'k_s=0.05:uniform' (+-5 %); spaces ignored, a
        part refused quoted as typed."""
        parts = spec_text.tolerance_parts(str(text))
        if parts is None:
            raise InvalidParameterError("tolerance", text, "NAME=REL or NAME=REL:normal|uniform", "has no =")
        name, value, dist = parts
        return cls.make(spec_text.name_text(name, PARAMETER_SPECS), spec_text.number_text(value),
                        spec_text.name_text("normal" if dist is None else dist, DISTRIBUTIONS))

    @classmethod
    def make(cls, name: str, relative: Any, distribution: str = "normal") -> "Tolerance":
        if name not in PARAMETER_SPECS:
            raise unknown_name_error(name, PARAMETER_SPECS)
        if distribution not in DISTRIBUTIONS:
            raise InvalidParameterError(f"tolerance {name} distribution", distribution, "normal or uniform")
        if PARAMETER_SPECS[name].integer:
            raise InvalidParameterError(f"tolerance {name}", relative, "a tolerance on a continuous parameter",
                                        f"{name} is an integer (a count), it has no tolerance")
        rel = check_number(f"tolerance {name}", relative, 0.0, TOLERANCE_LIMITS[distribution])
        return cls(name, rel, distribution)

    @property
    def std_factor(self) -> float:
        return self.relative if self.distribution == "normal" else self.relative / math.sqrt(3.0)

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "relative": self.relative, "distribution": self.distribution,
                "relative_std": self.std_factor}


def _growth(model, V: float, Fz: float) -> float:
    return float(np.max(np.linalg.eigvals(Linearisation(model, Fz).at(V)).real))


def _same_turning_point(found: tuple[float, float, float], nominal: tuple[float, float, float]) -> bool:
    """Whether Newton from the nominal lowest point (V, Fz, omega) found that point of the sample's curves
    (in the box, the same mode, near it) and not another turning point of Re lambda = d Re lambda/dV = 0."""
    V, Fz, omega = found
    V0, Fz0, omega0 = nominal
    return (V_BAND[0] <= V <= V_BAND[1] and FZ_BOX[0] <= Fz <= FZ_BOX[1] and abs(omega / omega0 - 1.0) < 0.1
            and abs(V / V0 - 1.0) < 0.5 and abs(Fz / Fz0 - 1.0) < 0.5)


def _disturbed(config: str, params: Parameters, disturbance: tuple[float, str]) -> dict[str, dict[str, Any]]:
    """At each operating point the modes of the shimmy attractors a disturbance up to the size reaches (margins on
    the point's diagram, in this process): {point: {"modes": [...], "unsettled": runs}}."""
    from ..core.executors import InlineExecutor
    from ..maps.margins import diagram_at, margins
    from ...model.parameters import DIAGRAM_V_RANGE

    size, direction = disturbance
    out: dict[str, dict[str, Any]] = {}
    diagrams: dict[float, Any] = {}
    for point, (V, Fz) in OPERATING_POINTS.items():
        if Fz not in diagrams:  # each sample's own, asked only here: not kept in the process's cache
            v_max = max(DIAGRAM_V_RANGE[1], *(v for v, f in OPERATING_POINTS.values() if f == Fz))
            diagrams[Fz] = diagram_at.__wrapped__(Configuration.parse(config), Fz, params, v_max)
        found = margins(config, V, Fz, params=params, diagram=diagrams[Fz], executor=InlineExecutor(),
                        direction=direction, max_size=size)
        modes = [a["mode"] for a in found.attractors if a["kind"] != "equilibrium" and a["min_disturbance"]["reached"]]
        out[point] = {"modes": modes, "unsettled": found.unsettled}
    return out


def _sample_unit(task: tuple) -> list[dict[str, Any]]:
    """Figures of a chunk of samples: (config, base params, names, rows of values, Fz, nominal lowest point of
    the Hopf curves (V, Fz, omega) or None[, disturbance (size, direction) or None])."""
    config, base, names, rows, Fz, low, *rest = task
    disturbance = rest[0] if rest else None
    out = []
    for values in rows:
        try:  # samples may reach past a design range (not past physics): the statistics are not truncated
            params = Parameters.from_dict(base).with_sampled(dict(zip(names, values, strict=True)))
        except InvalidParameterError as exc:
            out.append({"ok": False, "reason": str(exc)})
            continue
        model = build_model(config, params)
        speeds = [h.V for h in hopf_points(config, Fz, params=params, v_range=(V_BAND[0], V_BAND[1])).hopf_points]
        entry: dict[str, Any] = {"ok": True, "hopf": speeds}
        entry["min_shimmy_Fz"] = None
        if low == "curves":  # the nominal lowest point is on an edge of the box: each sample's own curves
            from ..diagrams.hopf_curves import hopf_curves

            found = hopf_curves(config, params=params, v_range=V_BAND, fz_range=FZ_BOX).fz_minimum
            entry["min_shimmy_Fz"] = None if found is None else found["Fz"]
        elif low:
            try:
                V_low, Fz_low, omega_low = polish_lowest_point(model, low[0], low[1])
            except (ConvergenceError, np.linalg.LinAlgError):
                V_low, Fz_low, omega_low = math.nan, math.nan, math.nan
            if _same_turning_point((V_low, Fz_low, omega_low), low):
                entry["min_shimmy_Fz"] = Fz_low
            else:  # Newton from the nominal point went to another turning point (another mode, Fz < 0): continue
                # this sample's curves
                from ..diagrams.hopf_curves import hopf_curves

                found = hopf_curves(config, params=params, v_range=V_BAND, fz_range=FZ_BOX).fz_minimum
                entry["min_shimmy_Fz"] = None if found is None else found["Fz"]
                entry["min_recomputed"] = True
        entry["unstable"] = {p: _growth(model, V, F) > 0.0 for p, (V, F) in OPERATING_POINTS.items()}
        if disturbance is not None:
            entry["disturbed"] = _disturbed(config, params, disturbance)
        out.append(entry)
    return out


def _linear_probability(model, V: float, Fz: float, pairs, names, sigma) -> float:
    """P(some eigenvalue of x = 0 has Re > 0) at (V, Fz) to first order: each eigenvalue's real part
    g_k + sum_i (d Re lambda_k / d theta_i) sigma_i xi_i is normal; the most likely one to cross decides,
    P = Phi(max_k g_k / s_k) (a lower bound of the union, exact when one eigenvalue dominates)."""
    J = Linearisation(model, Fz).at(V)
    ev, vl, vr = scipy.linalg.eig(J, left=True, right=True)
    dJ = jacobian_derivatives(model, V, Fz, pairs)
    best = -math.inf
    for k in np.nonzero(ev.imag >= 0)[0]:
        q, w = vr[:, k], vl[:, k]
        scale = np.conj(w) @ q
        d = np.array([(np.conj(w) @ dJ[n] @ q / scale).real for n in names])
        s = float(np.sqrt(np.sum((d * sigma) ** 2)))
        g = float(ev[k].real)
        z = g / s if s > 0 else (math.inf if g > 0 else -math.inf)
        best = max(best, z)
    return float(norm.cdf(best))


def _stats(values: np.ndarray, nominal: float, linear_std: float | None) -> dict[str, Any]:
    values = np.asarray(values, float)
    return {"nominal": nominal, "mean": float(values.mean()), "std": float(values.std(ddof=1)) if values.size > 1
            else 0.0, "p05": float(np.quantile(values, 0.05)), "p95": float(np.quantile(values, 0.95)),
            "min": float(values.min()), "max": float(values.max()), "linear_std": linear_std,
            "linear_p05": None if linear_std is None else nominal - 1.6448536269514722 * linear_std,
            "linear_p95": None if linear_std is None else nominal + 1.6448536269514722 * linear_std,
            "samples": values.tolist()}


def _share(count: int, n: int) -> dict[str, Any]:
    from ..core.basins import wilson

    return {"p": count / n, "count": count, "samples": n, "ci95": list(wilson(count, n))}


def _disturbed_shares(ok: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per point: P(shimmy after a disturbance up to the size: x = 0 unstable or a shimmy attractor reached) and
    P(each mode reached), with their intervals, and the samples linearly unstable there."""
    n = len(ok)
    out = {}
    for p in OPERATING_POINTS:
        reached = [set(e["disturbed"][p]["modes"]) for e in ok]
        shimmy = sum(e["unstable"][p] or bool(r) for e, r in zip(ok, reached, strict=True))
        modes = {m: _share(sum(m in r for r in reached), n) for m in ("torsional", "lateral", "both")}
        modes |= {m: _share(sum(m in r for r in reached), n) for m in sorted(set().union(*reached)) if m not in modes}
        out[p] = {**_share(shimmy, n), "linearly_unstable": sum(e["unstable"][p] for e in ok), "modes": modes}
    return out


@dataclass
class RobustnessResult:
    config: Configuration
    Fz: float
    params: Parameters
    tolerances: list[Tolerance]
    samples: int
    seed: int
    hopf_points: list[dict[str, Any]]
    min_shimmy: dict[str, Any] | None
    p_shimmy: dict[str, float]
    p_shimmy_linear: dict[str, float | None]
    refused: int
    elapsed_s: float
    executor: str
    warnings: list[str] = field(default_factory=list)
    p_shimmy_ci95: dict[str, list[float]] = field(default_factory=dict)
    disturbance: dict[str, Any] | None = None  # size, unit, direction
    p_shimmy_disturbed: dict[str, dict[str, Any]] | None = None

    def to_dict(self) -> dict[str, Any]:
        methods = {}
        if self.disturbance is not None:
            methods["p_shimmy_disturbed"] = (
                f"share of samples where straight rolling is unstable at the point or a shimmy attractor is reached "
                f"by a disturbance from straight rolling along {self.disturbance['direction']} of at most "
                f"{self.disturbance['size']:g} rad (as the yaw angle of the same energy), and of those where each "
                "mode is reached: the margins at the point (bracketing scan of 12 sizes up to it, bisection, each "
                "run classified by the attractors of the sample's bifurcation diagram at the load); 95 % Wilson "
                "intervals")
        return {"config": self.config.value, "Fz": self.Fz, "params": self.params.to_dict(),
                "tolerances": [t.to_dict() for t in self.tolerances], "samples": self.samples, "seed": self.seed,
                "hopf_points": self.hopf_points, "min_shimmy_Fz": self.min_shimmy, "p_shimmy": self.p_shimmy,
                "p_shimmy_ci95": self.p_shimmy_ci95, "p_shimmy_linear": self.p_shimmy_linear,
                "disturbance": self.disturbance, "p_shimmy_disturbed": self.p_shimmy_disturbed,
                "operating_points": {k: {"V": v[0], "Fz": v[1]} for k, v in OPERATING_POINTS.items()},
                "refused_samples": self.refused, "elapsed_s": self.elapsed_s, "executor": self.executor,
                "warnings": self.warnings,
                "methods": {"samples": "scrambled Sobol sequence (seeded), inverse normal CDF for normal tolerances",
                            "p_shimmy": "share of samples where straight rolling is unstable at the point "
                                        "(linear shimmy; bistable points not counted), 95 % Wilson intervals",
                            "linear": "first-order propagation of the implicit-differentiation sensitivities",
                            **methods},
                "version": __version__}

    def summary_text(self) -> str:
        """The table ``python -m shimmy robustness`` prints
        (:func:`~shimmy.analyses.decisions.summaries.robustness_summary`)."""
        return robustness_summary(self.to_dict())


def robustness(config: Configuration | str, tolerances: Sequence[Tolerance | str] | Mapping[str, float],
               *, samples: int = 128, Fz: float = DEFAULT_FZ, params: Parameters | None = None, seed: int = 0,
               disturbance: float | None = None, disturbance_direction: str = "psi",
               executor=None, progress: Callable[[float, str], None] | None = None) -> RobustnessResult:
    """Distributions of the Hopf speeds at ``Fz``, of the minimum shimmy load and of shimmy at the nine
    operating points under ``tolerances``, sampled and by linear propagation; with ``disturbance`` (rad, as the
    yaw angle of the same energy, along ``disturbance_direction``) also P(shimmy) counting every shimmy attractor
    a disturbance up to that size reaches (module docstring)."""
    from ..maps.margin_options import DIRECTIONS, LIMITS

    clock = time.perf_counter()
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    Fz = check_number("Fz", Fz, *FZ_RANGE, "N")
    samples = int(check_number("samples", samples, 2, 4096, integer=True))
    seed = int(check_number("seed", seed, 0, 2 ** 31 - 1, integer=True))
    if disturbance is not None:
        low, high, unit, _ = LIMITS["max_size"]
        disturbance = check_number("disturbance", disturbance, low, high, f"{unit} (as the yaw angle of the same "
                                                                          "energy)")
        if disturbance_direction not in DIRECTIONS:
            raise unknown_name_error(str(disturbance_direction), DIRECTIONS, "disturbance_direction")
    if isinstance(tolerances, Mapping):
        tols = [Tolerance.make(k, v) for k, v in tolerances.items()]
    else:
        tols = [t if isinstance(t, Tolerance) else Tolerance.parse(t) for t in tolerances]
    if not tols:
        raise InvalidParameterError("tolerance", [], "one or more NAME=REL tolerances")
    names = [t.name for t in tols]
    if len(set(names)) != len(names):
        raise InvalidParameterError("tolerance", names, "each parameter at most once")
    unused = [n for n in names if not affects(n, config)]
    warnings = [f"{n} is not fitted in configuration {config.value}: its tolerance has no effect" for n in unused]
    if executor is None:
        with open_executor() as own:
            return robustness(config, tols, samples=samples, Fz=Fz, params=params, seed=seed, disturbance=disturbance,
                              disturbance_direction=disturbance_direction, executor=own, progress=progress)
    report = progress or (lambda fraction, message: None)
    model = build_model(config, params)
    pairs = coefficient_pairs(config, params, names)
    nominal_speeds = [h.V for h in hopf_points(config, Fz, params=params, v_range=(V_BAND[0], V_BAND[1])).hopf_points]
    hopf_sens = hopf_sensitivities(model, Fz, nominal_speeds, pairs)
    low = min_shimmy_sensitivity(model, pairs, FZ_BOX)
    sigma = np.array([float(getattr(params, t.name)) * t.std_factor for t in tols])

    def linear_std(derivatives: dict[str, float]) -> float:
        return float(np.sqrt(np.sum((np.array([derivatives[n] for n in names]) * sigma) ** 2)))

    # Samples: scrambled Sobol in (0, 1)^d -> xi.
    m = math.ceil(math.log2(samples))
    u = qmc.Sobol(len(tols), scramble=True, seed=seed).random_base2(m)[:samples]
    u = np.clip(u, 1e-12, 1 - 1e-12)
    xi = np.column_stack([norm.ppf(u[:, k]) if t.distribution == "normal" else 2 * u[:, k] - 1
                          for k, t in enumerate(tols)])
    nominal = np.array([float(getattr(params, n)) for n in names])
    rows = (nominal * (1.0 + xi * np.array([t.relative for t in tols]))).tolist()
    start: Any = None  # no Hopf curve in the box at the nominal design: no minimum shimmy load to sample
    if low is not None:
        start = ((low["V"], low["Fz"], 2 * math.pi * low["frequency_hz"])
                 if low["source"] == "lowest point of the Hopf curves" else "curves")
    size = CHUNK if disturbance is None else CHUNK_DISTURBED
    chunks = [rows[k:k + size] for k in range(0, len(rows), size)]
    report(0.02, f"{samples} samples in {len(chunks)} units")
    extra = () if disturbance is None else ((disturbance, disturbance_direction),)
    results = run_units(_sample_unit, [(config.value, params.to_dict(), names, c, Fz, start, *extra) for c in chunks],
                        executor, lambda f, msg: report(0.02 + 0.93 * f, f"samples: {msg}"),
                        lambda t: f"{len(t[3])} samples")
    flat = [e for chunk in results for e in chunk]
    ok = [e for e in flat if e["ok"]]
    refused = len(flat) - len(ok)
    if refused:
        first = next(e["reason"] for e in flat if not e["ok"])
        warnings.append(f"{refused} of {len(flat)} samples are not physical and are left out (for example: {first})")
    if not ok:
        raise ConvergenceError("no sample could be evaluated: " + flat[0]["reason"])
    recomputed = sum(bool(e.get("min_recomputed")) for e in ok)
    if recomputed:
        warnings.append(f"{recomputed} of {len(ok)} samples: Newton from the nominal lowest point of the Hopf curves "
                        "did not converge or reached another turning point; their minimum shimmy load was found by "
                        "continuing their curves")
    hopf_out = []
    same = [e for e in ok if len(e["hopf"]) == len(nominal_speeds)]
    if len(same) < len(ok):
        warnings.append(f"{len(ok) - len(same)} samples have another number of Hopf points at {Fz / 1e3:g} kN than "
                        f"the nominal design ({len(nominal_speeds)}); their speeds are left out of the statistics")
    for k, V0 in enumerate(nominal_speeds):
        if same:
            stats = _stats(np.array([e["hopf"][k] for e in same]), V0, linear_std(hopf_sens[k]["dV_dp"]))
            hopf_out.append(stats)
    lows = np.array([e["min_shimmy_Fz"] for e in ok if e["min_shimmy_Fz"] is not None])
    if start is not None and lows.size < len(ok):
        warnings.append(f"{len(ok) - lows.size} of {len(ok)} samples have no Hopf curve in the box; they are left "
                        "out of the minimum shimmy load's statistics")
    if not same:
        warnings.append(f"no sample has the nominal design's {len(nominal_speeds)} Hopf points at {Fz / 1e3:g} kN: "
                        "no Hopf-speed statistics")
    low_out = None
    if low and lows.size:
        low_out = _stats(lows, low["Fz"], linear_std(low["dFz_dp"]) if low["dFz_dp"] is not None else None)
    p_sampled = {p: float(np.mean([e["unstable"][p] for e in ok])) for p in OPERATING_POINTS}
    p_ci = {p: _share(sum(e["unstable"][p] for e in ok), len(ok))["ci95"] for p in OPERATING_POINTS}
    p_linear = {p: _linear_probability(model, V, F, pairs, names, sigma) for p, (V, F) in OPERATING_POINTS.items()}
    disturbed = None
    if disturbance is not None:
        disturbed = _disturbed_shares(ok)
        unsettled = sum(d["unsettled"] for e in ok for d in e["disturbed"].values())
        if unsettled:
            warnings.append(f"{unsettled} runs of the margins settled on no attractor in the time allowed (counted "
                            "as not reaching one)")
    report(1.0, "done")
    return RobustnessResult(config, Fz, params, tols, samples, seed, hopf_out, low_out, p_sampled, p_linear, refused,
                            time.perf_counter() - clock, type(executor).__name__, warnings, p_ci,
                            None if disturbance is None else {"size": disturbance, "unit": "rad",
                                                              "direction": disturbance_direction},
                            disturbed)
