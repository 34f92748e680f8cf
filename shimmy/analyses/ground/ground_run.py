"""Ground runs: the gear through a take-off, a landing roll or a taxi, V(t) and Fz(t) from a profile.

:func:`ground_run` integrates the non-autonomous equations with the compiled integrator
(:func:`shimmy.model.integrator.integrate_profile`: the same Dormand-Prince 5(4), tolerances,
output grid and failure reporting as :func:`~shimmy.analyses.core.simulation.simulate`; a constant
profile gives the same history) and reports what a landing-gear engineer asks of a run:

* **Envelopes** of the torsional angle psi (rad) and the lateral bending displacement
  l_g delta (m): max |x| over a centred window of ``envelope_window`` (0.15 s, at least one
  period of the shimmy modes, 6-16 Hz), so the envelope leads a growing oscillation and lags a
  dying one by at most half that window.
* **Time in shimmy**: how long either envelope is above its threshold (0.01 rad, 1 mm by
  default), the intervals and the speed range they cover.
* **Peaks** of |psi| and |l_g delta| and where (t, V, Fz) they occurred.
* **Boundary crossings** of the Hopf curves: the times at which an eigenvalue pair of straight
  rolling x = 0 crosses the imaginary axis along the trajectory (V(t), Fz(t)): the number of
  unstable eigenvalues on a 0.05 s grid (and at every table point), each change located by
  bisection to 1e-9 s. These are the trajectory's intersections with the Hopf curves of
  :mod:`shimmy.analyses.diagrams.hopf_curves`, found without continuing them (a test checks each lies on
  a continued curve). With ``cycle_curves=True`` also the crossings of the fold-of-cycles and
  torus curves of :mod:`shimmy.analyses.diagrams.cycle_curves` (tens of seconds per configuration the
  first time: the curves are continued over the whole load range; then kept for the process):
  intersections of the trajectory's table segments with the curves' polylines.
* **Onset delay**: from each crossing into the unstable region (x = 0 losing stability) to the
  first moment |psi| or |l_g delta| itself exceeds its threshold. A slowly varying parameter
  delays the onset well past the static Hopf point (the oscillation grows from the small
  amplitude left by the stable stretch before it), and a faster ramp moves it further in V.
* **A kick** (optional, :class:`~shimmy.analyses.ground.kicks.Kick`): a jump of the yaw angle or
  the yaw rate at a chosen time or speed (a runway joint, a touchdown with yaw). The integration
  is split at that instant and the jump applied there, and the run says whether shimmy started
  after it and in which mode (:func:`~shimmy.analyses.ground.kicks.kick_outcome`).

:func:`ground_runs` runs one profile for several configurations and compares them with
``original``.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np
from scipy.ndimage import maximum_filter1d

from ...version import __version__
from ...continuation import PointKind
from ...errors import InvalidParameterError
from ...model import integrator
from ...model.configurations import ALL_CONFIGURATIONS, Configuration
from ...model.equations import build_model, jacobian
from ...model.parameters import DIAGRAM_V_RANGE, FZ_RANGE, V_RANGE, Parameters, check_number
from .ground_profiles import GroundProfile, as_profile
from .kicks import KICK_PRESETS, SAME_INSTANT, Kick, kick_instant, kick_outcome, scenario
from .summaries import comparison_dict, comparison_summary, comparison_table, ground_run_summary
from ..core import nes_range
from ..core.response import dominant_mode, torsional_share
from ..core.simulation import STATUS_MESSAGES, SimulationOptions, initial_state

CROSSING_GRID = 0.05  # s: spacing of the eigenvalue checks along the trajectory
CROSSING_TOL = 1e-9  # s


@dataclass(frozen=True)
class GroundRunOptions:
    """Numerical settings and thresholds of a ground run (validated at construction).

    dt_out, rtol, atol, max_steps, exact_nes: as :class:`~shimmy.analyses.core.simulation.SimulationOptions`.
    psi_threshold (rad, 1e-6 to 1) and lateral_threshold (m, of l_g delta, 1e-7 to 1): the envelope
    above either counts as shimmy. envelope_window (s, 0.01 to 5): the centred window of the
    envelopes' running maximum. cycle_curves: also the crossings of the fold and torus curves.
    """

    dt_out: float = 0.001
    rtol: float = 1e-7
    atol: float = 1e-10
    max_steps: int = 10_000_000
    exact_nes: bool = False
    psi_threshold: float = 0.01  # rad
    lateral_threshold: float = 0.001  # m
    envelope_window: float = 0.15  # s
    cycle_curves: bool = False

    def __post_init__(self):
        # the integrator's settings are checked exactly as a time history's are
        SimulationOptions(t_end=1.0, dt_out=self.dt_out, rtol=self.rtol, atol=self.atol, max_steps=self.max_steps,
                          exact_nes=self.exact_nes)
        object.__setattr__(self, "max_steps", int(self.max_steps))
        object.__setattr__(self, "psi_threshold", check_number("psi_threshold", self.psi_threshold, 1e-6, 1.0, "rad"))
        object.__setattr__(self, "lateral_threshold",
                           check_number("lateral_threshold", self.lateral_threshold, 1e-7, 1.0, "m"))
        object.__setattr__(self, "envelope_window",
                           check_number("envelope_window", self.envelope_window, 0.01, 5.0, "s"))
        if not isinstance(self.cycle_curves, bool):
            raise InvalidParameterError("cycle_curves", self.cycle_curves, "true or false", "is not a boolean")

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass(frozen=True)
class GroundRunResult:
    """A ground run with its measures and how the integration went (times in s from the profile's clock)."""

    config: Configuration
    profile: GroundProfile
    params: Parameters
    options: GroundRunOptions
    t: np.ndarray
    V: np.ndarray
    Fz: np.ndarray
    states: np.ndarray  # (n_states, n_samples)
    envelope_psi: np.ndarray
    envelope_lateral: np.ndarray
    time_in_shimmy_s: float
    shimmy_intervals: list[dict[str, float]]
    speed_range: list[float] | None  # [V_min, V_max] covered in shimmy (m/s)
    peak_psi: dict[str, float]
    peak_lateral: dict[str, float]
    boundary_crossings: list[dict[str, Any]]
    onsets: list[dict[str, Any]]
    success: bool
    status: int
    message: str
    counters: dict[str, int] = field(default_factory=dict)
    elapsed_s: float = 0.0
    warnings: list[str] = field(default_factory=list)
    kick: dict[str, Any] | None = None  # the kick and what followed it (kicks.kick_outcome), None without one

    @property
    def psi(self) -> np.ndarray:
        return self.states[0]

    @property
    def lateral(self) -> np.ndarray:
        """Lateral bending displacement l_g * delta (m)."""
        return self.params.gear.l_g * self.states[2]

    @property
    def onset_delay_s(self) -> float | None:
        """Delay of the first onset that follows a crossing into the unstable region (None if none)."""
        for o in self.onsets:
            if o["delay_s"] is not None:
                return o["delay_s"]
        return None

    def series(self, stride: int = 1) -> dict[str, list[float]]:
        cols = {"t": self.t, "V": self.V, "Fz": self.Fz, "psi": self.psi, "lateral": self.lateral,
                "envelope_psi": self.envelope_psi, "envelope_lateral": self.envelope_lateral}
        if self.config.has_nes:
            cols["psis"], cols["dpsis"] = self.states[5], self.states[6]
            cols["nes_relative"] = self.states[0] - self.states[5]
        return {k: v[::stride].tolist() for k, v in cols.items()}

    def summary(self) -> dict[str, Any]:
        return {"config": self.config.value, "time_in_shimmy_s": self.time_in_shimmy_s,
                "shimmy_intervals": self.shimmy_intervals, "speed_range": self.speed_range,
                "peak_psi": self.peak_psi, "peak_lateral": self.peak_lateral,
                "boundary_crossings": self.boundary_crossings, "onsets": self.onsets,
                "onset_delay_s": self.onset_delay_s, "kick": self.kick, "success": self.success,
                "message": self.message}

    def to_dict(self, series_stride: int = 1, include_series: bool = True) -> dict[str, Any]:
        out = {**self.summary(), "profile": self.profile.to_dict(), "options": self.options.to_dict(),
               "params": self.params.to_dict(), "counters": dict(self.counters), "elapsed_s": self.elapsed_s,
               "warnings": list(self.warnings), "version": __version__}
        if include_series:
            out.update(self.series(series_stride))
            out["series_dt"] = series_stride * self.options.dt_out
        return out

    def summary_text(self, header: bool = True) -> str:
        """The lines ``python -m shimmy ground-run`` prints for this run; with ``header``, the profile and the
        thresholds first (:func:`~shimmy.analyses.ground.summaries.ground_run_summary`)."""
        return ground_run_summary(self.to_dict(include_series=False), header)


def ground_run(config: Configuration | str, profile: Any, *, params: Parameters | None = None, x0=None,
               options: GroundRunOptions | None = None, preset_options: dict[str, Any] | None = None,
               kick: Kick | dict[str, Any] | None = None, **option_overrides) -> GroundRunResult:
    """Integrate the gear through ``profile`` (a :class:`GroundProfile`, a preset name "takeoff" /
    "landing" / "taxi" with ``preset_options``, a scenario "runway_joint" / "touchdown_yaw": a preset with
    a kick, or rows [t (s), V (m/s), Fz (N)]).

    ``x0`` defaults to psi = 0.001 rad, all else zero (as :func:`simulate`). ``kick``: a
    :class:`~shimmy.analyses.ground.kicks.Kick`, or its request fields {kick, kick_size, kick_at_time |
    kick_at_speed}; the jump is added to the state at its instant. Bad profiles, kicks and options raise
    :class:`InvalidParameterError` before any work; integration failures come back as ``success=False``
    with a message and the part computed.
    """
    config = Configuration.parse(config)
    profile, kick = _with_scenario(profile, kick)
    profile = as_profile(profile, preset_options)
    params = params if params is not None else Parameters()
    options = options or GroundRunOptions()
    if option_overrides:
        options = GroundRunOptions(**{**options.to_dict(), **option_overrides})
    t_kick = kick_instant(kick, profile) if kick is not None else None
    model = build_model(config, params, exact_nes=options.exact_nes)
    n = model.n_states
    start = initial_state(x0, n)

    clock = time.perf_counter()
    t0 = float(profile.t[0])
    n_out = int(math.floor(profile.duration / options.dt_out + 1e-9)) + 1
    out = np.empty((n_out, integrator.N_FULL))
    run = _Integration(profile, model, options)
    before = after = without = None
    if kick is None:
        written = run.grid(start, t0, out)
    else:
        # the samples before the kick and the state at it (the same steps: the kick is a row of both tables),
        # then the run from the kicked state, and beside it the run from the same state without the kick
        span = t_kick - t0
        first = 0 if span <= SAME_INSTANT else min(n_out, int(math.ceil(span / options.dt_out - 1e-9)))
        written = run.grid(start, t0, out[:first], stop=span)
        before = run.exact(start, t0, t_kick) if written == first else None
        if before is not None:
            after = before.copy()
            after[kick.index] += kick.size
            written += run.onward(after, t_kick, first, out[first:])
            base = _Integration(profile, model, options)
            rows = np.empty((n_out - first, integrator.N_FULL))
            without = np.concatenate([out[:first, :n], rows[:base.onward(before, t_kick, first, rows), :n]]).T
    status, (accepted, rejected, calls) = run.status, run.counters
    integration_s = time.perf_counter() - clock

    t = t0 + np.arange(written) * options.dt_out
    V, Fz = profile.at(t)
    states = np.ascontiguousarray(out[:written, :n].T)
    lateral = params.gear.l_g * states[2]
    width = max(1, int(round(options.envelope_window / options.dt_out)) | 1)
    envelope_psi = maximum_filter1d(np.abs(states[0]), width, mode="nearest")
    envelope_lateral = maximum_filter1d(np.abs(lateral), width, mode="nearest")

    shimmy = _in_shimmy(states, params.gear.l_g, width, options)
    intervals = _intervals(shimmy, t, V, options.dt_out)
    in_shimmy = float(np.count_nonzero(shimmy) * options.dt_out)
    speed_range = [float(V[shimmy].min()), float(V[shimmy].max())] if shimmy.any() else None

    crossings = hopf_crossings(config, profile, params=params, t_end=t[-1] if written else t0)
    warnings: list[str] = []
    if options.cycle_curves:
        try:
            crossings += cycle_curve_crossings(config, profile, params=params, t_end=t[-1] if written else t0)
        except Exception as exc:  # noqa: BLE001 - the run stands without them; say why they are missing
            warnings.append(f"fold and torus crossings not computed: {exc}")
        crossings.sort(key=lambda c: c["t"])
    beyond = nes_range.warning(config, params, nes_range.rotation_peak(states), options.exact_nes)
    if beyond:
        warnings.append(beyond)
    above = (np.abs(states[0]) > options.psi_threshold) | (np.abs(lateral) > options.lateral_threshold)
    onsets = _onsets(crossings, above, shimmy, t, V, Fz)
    outcome = None
    if kick is not None:
        if before is None:  # the integration failed before the kick
            outcome = {**kick.to_dict(), "t": t_kick, "applied": False, "shimmy_started": None, "mode": None,
                       "note": "not applied: the integration stopped before the kick"}
        else:
            # time in shimmy from the kick on, with the kick against without it (as far as both got)
            i, m = min(first, written), min(written, without.shape[1])
            extra = (np.count_nonzero(shimmy[i:m]) - np.count_nonzero(_in_shimmy(without, params.gear.l_g, width,
                                                                                  options)[i:m])) * options.dt_out
            outcome = {**kick_outcome(kick, t_kick, before, after, t, V, Fz, states, without,
                                      k_psi=params.gear.k_psi, k_delta=params.gear.k_delta, l_g=params.gear.l_g,
                                      psi_threshold=options.psi_threshold,
                                      lateral_threshold=options.lateral_threshold),
                       "applied": True, "extra_time_in_shimmy_s": float(extra)}
    return GroundRunResult(
        config=config, profile=profile, params=params, options=options, t=t, V=V, Fz=Fz, states=states,
        envelope_psi=envelope_psi, envelope_lateral=envelope_lateral, time_in_shimmy_s=in_shimmy,
        shimmy_intervals=intervals, speed_range=speed_range,
        peak_psi=_peak(np.abs(states[0]), t, V, Fz), peak_lateral=_peak(np.abs(lateral), t, V, Fz),
        boundary_crossings=crossings, onsets=onsets, success=status == integrator.SUCCESS, status=int(status),
        message=STATUS_MESSAGES[status],
        counters={"steps": int(accepted), "rejected": int(rejected), "rhs_calls": int(calls),
                  "integration_ms": int(round(1e3 * integration_s))},
        elapsed_s=time.perf_counter() - clock, warnings=warnings, kick=outcome)


def _with_scenario(profile: Any, kick: Kick | dict[str, Any] | None) -> tuple[Any, Kick | None]:
    """A scenario's name (:data:`~shimmy.analyses.ground.kicks.KICK_PRESETS`) as its profile preset and its kick (a
    kick given as fields replacing the scenario's fields); a kick given as fields as a :class:`Kick`."""
    if isinstance(profile, str) and profile in KICK_PRESETS:
        if isinstance(kick, Kick):
            return KICK_PRESETS[profile]["preset"], kick
        profile, kick = scenario(profile, kick)
    return profile, Kick.of(kick) if isinstance(kick, dict) else kick


class _Integration:
    """The compiled integrator through a profile in pieces on the output grid t0 + k dt_out (k = 0, 1, ...): runs
    on the grid from a sample, and the state at any instant with the last step ending on it, so that a jump of
    the state is applied at its instant however it falls on the grid. Counts the steps of every piece; after a
    failure, ``status`` says which and nothing more is integrated."""

    def __init__(self, profile: GroundProfile, model, options: GroundRunOptions):
        self.profile, self.model, self.options = profile, model, options
        self.t0 = float(profile.t[0])
        self.status = integrator.SUCCESS
        self.counters = (0, 0, 0)

    def _table(self, t_from: float, stop: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The profile's rows after ``t_from`` on a clock starting there, with a row at ``stop`` (that clock) that
        is never the last (the integrator ends a step on every interior row)."""
        p = self.profile
        later = p.t > t_from + SAME_INSTANT
        V_from, Fz_from = p.at(t_from)
        local = np.concatenate([[0.0], p.t[later] - t_from])
        V, Fz = np.concatenate([[V_from], p.V[later]]), np.concatenate([[Fz_from], p.Fz[later]])
        if stop is not None:
            keep = np.abs(local - stop) > SAME_INSTANT
            local, V, Fz = local[keep], V[keep], Fz[keep]
            V_stop, Fz_stop = p.at(t_from + stop)
            i = int(np.searchsorted(local, stop))
            local, V, Fz = np.insert(local, i, stop), np.insert(V, i, V_stop), np.insert(Fz, i, Fz_stop)
            if i == local.size - 1:
                local, V, Fz = np.append(local, stop + 1.0), np.append(V, V_stop), np.append(Fz, Fz_stop)
        return local, V, Fz

    def _integrate(self, x: np.ndarray, table, dt: float, out: np.ndarray) -> int:
        o = self.options
        status, accepted, rejected, calls, written = integrator.integrate_profile(
            x, dt * (out.shape[0] - 1), dt, *table, self.model.coefficients, *self.model.flags, o.rtol, o.atol,
            o.max_steps, out)
        a, r, c = self.counters
        self.counters = (a + int(accepted), r + int(rejected), c + int(calls))
        if status != integrator.SUCCESS:
            self.status = status
        return int(written)

    def grid(self, x: np.ndarray, t_from: float, out: np.ndarray, stop: float | None = None) -> int:
        """The samples at ``t_from`` + k dt_out from state ``x`` there, into the rows of ``out``; how many were
        written. ``stop`` as in :meth:`_table` (a run sharing this one's steps ends a step there)."""
        if out.shape[0] == 0 or self.status != integrator.SUCCESS:
            return 0
        return self._integrate(x, self._table(t_from, stop), self.options.dt_out, out)

    def exact(self, x: np.ndarray, t_from: float, t_to: float) -> np.ndarray | None:
        """The state at ``t_to`` from ``x`` at ``t_from``, the last step ending on it (no interpolation); None after
        a failure."""
        span = t_to - t_from
        if span <= SAME_INSTANT:
            return x.copy()
        if self.status != integrator.SUCCESS:
            return None
        pair = np.empty((2, integrator.N_FULL))
        return pair[1].copy() if self._integrate(x, self._table(t_from, span), span, pair) == 2 else None

    def onward(self, x: np.ndarray, t_at: float, first: int, out: np.ndarray) -> int:
        """From state ``x`` at ``t_at`` (at or before sample ``first``), the samples ``first``, ``first`` + 1, ...
        into the rows of ``out``; how many were written."""
        sample = self.t0 + first * self.options.dt_out
        y = self.exact(x, t_at, sample) if out.shape[0] else None
        return 0 if y is None else self.grid(y, sample, out)


def _in_shimmy(states: np.ndarray, l_g: float, width: int, options: GroundRunOptions) -> np.ndarray:
    """Where either envelope (the running maximum over ``width`` samples) is above its threshold."""
    if states.shape[1] == 0:
        return np.zeros(0, dtype=bool)
    return ((maximum_filter1d(np.abs(states[0]), width, mode="nearest") > options.psi_threshold)
            | (maximum_filter1d(np.abs(l_g * states[2]), width, mode="nearest") > options.lateral_threshold))


def _peak(a: np.ndarray, t, V, Fz) -> dict[str, float]:
    if a.size == 0:
        return {"value": float("nan"), "t": float("nan"), "V": float("nan"), "Fz": float("nan")}
    i = int(np.argmax(a))
    return {"value": float(a[i]), "t": float(t[i]), "V": float(V[i]), "Fz": float(Fz[i])}


def _intervals(mask: np.ndarray, t, V, dt: float) -> list[dict[str, float]]:
    """The runs of ``mask`` as intervals with their start and end speeds."""
    if not mask.any():
        return []
    edges = np.diff(np.concatenate([[0], mask.view(np.int8), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [{"t_start": float(t[a]), "t_end": float(t[b] + dt), "V_start": float(V[a]), "V_end": float(V[b]),
             "duration_s": float((b - a + 1) * dt)} for a, b in zip(starts, ends, strict=True)]


def _onsets(crossings, above, shimmy, t, V, Fz) -> list[dict[str, Any]]:
    """For each entry into the unstable region (and for a run starting in it) the first sample after it
    where |psi| or |l_g delta| exceeds its threshold (``above``), unless the envelope is above it
    already at the entry (``shimmy``: the oscillation of an earlier stretch is still there)."""
    if t.size == 0:
        return []
    hopf = [c for c in crossings if c["curve"] == "hopf"]
    entries = [(c["t"], c["V"], c["Fz"], True) for c in hopf if c["unstable_before"] == 0 and c["unstable_after"] > 0]
    if hopf and hopf[0]["unstable_before"] > 0:  # the run starts where straight rolling is unstable
        entries.insert(0, (float(t[0]), float(V[0]), float(Fz[0]), False))
    out = []
    for tc, vc, fc, crossed in entries:
        i = int(np.searchsorted(t, tc))
        hits = np.flatnonzero(above[i:])
        entry = {"t_unstable": tc, "V_unstable": vc, "Fz_unstable": fc, "crossed": crossed,
                 "t_onset": None, "V_onset": None, "Fz_onset": None, "delay_s": None}
        if hits.size:
            j = i + int(hits[0])
            if not shimmy[min(i, shimmy.size - 1)]:  # already in shimmy at the crossing: no onset of its own
                entry.update(t_onset=float(t[j]), V_onset=float(V[j]), Fz_onset=float(Fz[j]),
                             delay_s=float(t[j] - tc) if crossed else None)
        out.append(entry)
    return out


def _unstable_counts(model, V, Fz) -> np.ndarray:
    J = jacobian(model, np.zeros((model.n_states, np.size(V))), np.atleast_1d(V), np.atleast_1d(Fz))
    ev = np.linalg.eigvals(J)
    return np.count_nonzero(ev.real > 0.0, axis=-1)


def hopf_crossings(config: Configuration, profile: GroundProfile, *, params: Parameters,
                   t_end: float | None = None) -> list[dict[str, Any]]:
    """Where the trajectory (V(t), Fz(t)) crosses a Hopf curve: each change of the number of unstable
    eigenvalues of x = 0, located by bisection to 1e-9 s, with the mode of the crossing pair."""
    model = build_model(config, params)
    t_end = profile.t[-1] if t_end is None else t_end
    grid = np.union1d(np.arange(profile.t[0], t_end, CROSSING_GRID), profile.t[profile.t <= t_end])
    grid = np.union1d(grid, [t_end])
    counts = _unstable_counts(model, *profile.at(grid))
    changes = np.flatnonzero(np.diff(counts))
    out = []

    def count_at(tt: float) -> int:
        return int(_unstable_counts(model, *profile.at(np.array([tt])))[0])

    def locate(a: float, ca: int, b: float, cb: int) -> None:
        if ca == cb:
            return
        if b - a <= CROSSING_TOL:
            out.append((0.5 * (a + b), ca, cb))
            return
        m = 0.5 * (a + b)
        cm = count_at(m)
        locate(a, ca, m, cm)
        locate(m, cm, b, cb)

    for k in changes:
        locate(float(grid[k]), int(counts[k]), float(grid[k + 1]), int(counts[k + 1]))
    crossings = []
    k_psi, k_delta = params.gear.k_psi, params.gear.k_delta
    for tc, before, after in out:
        V, Fz = (float(v[0]) for v in profile.at(np.array([tc])))
        ev, vectors = np.linalg.eig(jacobian(model, np.zeros(model.n_states), V, Fz))
        i = int(np.argmin(np.abs(ev.real) + 1e-3 * (np.abs(ev.imag) == 0)))
        q = vectors[:, i]
        share = float(torsional_share(abs(q[0]), abs(q[2]), k_psi, k_delta))
        crossings.append({"t": tc, "V": V, "Fz": Fz, "curve": "hopf",
                          "mode": dominant_mode(share),
                          "frequency_hz": abs(float(ev[i].imag)) / (2 * math.pi),
                          "direction": "destabilising" if after > before else "stabilising",
                          "unstable_before": before, "unstable_after": after})
    return crossings


@functools.lru_cache(maxsize=16)
def _cycle_curve_polylines(config: Configuration, params: Parameters, v_max: float) -> tuple:
    """(kind, points (k, 2)) of every fold and torus curve in V 1..v_max, the full Fz range (kept per process)."""
    from ..diagrams.cycle_curves import cycle_curves

    result = cycle_curves(config, params=params, v_range=(V_RANGE[0], v_max), fz_range=FZ_RANGE,
                          kinds=(PointKind.FOLD_OF_CYCLES, PointKind.TORUS))
    return tuple((c.kind, np.array(c.curve.p, dtype=float)) for c in result.curves if len(c.curve.p) > 1)


CURVE_NAMES = {PointKind.FOLD_OF_CYCLES: "fold", PointKind.TORUS: "torus"}


def cycle_curve_crossings(config: Configuration, profile: GroundProfile, *, params: Parameters,
                          t_end: float | None = None) -> list[dict[str, Any]]:
    """Intersections of the trajectory's table segments with the fold and torus curves' polylines."""
    t_end = profile.t[-1] if t_end is None else t_end
    v_max = float(min(V_RANGE[1], max(DIAGRAM_V_RANGE[1], 1.1 * profile.V.max())))
    scale = np.array([10.0, 1e5])
    times = np.union1d(profile.t[profile.t < t_end], [t_end])
    path = np.column_stack(profile.at(times)) / scale
    out = []
    for kind, points in _cycle_curve_polylines(config, params, v_max):
        q = points / scale
        for j in range(len(path) - 1):
            for s, _ in _segment_hits(path[j], path[j + 1], q):
                tc = float(times[j] + s * (times[j + 1] - times[j]))
                V, Fz = (float(v) for v in (path[j] + s * (path[j + 1] - path[j])) * scale)
                out.append({"t": tc, "V": V, "Fz": Fz, "curve": CURVE_NAMES[kind]})
    return out


def _segment_hits(a: np.ndarray, b: np.ndarray, q: np.ndarray) -> list[tuple[float, float]]:
    """(s along a-b, u along the polyline segment) of each intersection of segment a-b with polyline q."""
    d = b - a
    e = q[1:] - q[:-1]
    denom = d[0] * e[:, 1] - d[1] * e[:, 0]
    w = q[:-1] - a
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0]) / denom
        u = (w[:, 0] * d[1] - w[:, 1] * d[0]) / denom
    hit = (denom != 0) & (s >= 0) & (s < 1) & (u >= 0) & (u < 1)
    return [(float(s[i]), float(u[i])) for i in np.flatnonzero(hit)]


@dataclass(frozen=True)
class GroundRunComparison:
    """One profile run for several configurations, each measure against ``original``.

    :meth:`table` gives one row per configuration (time in shimmy, peaks, onset delay, speed range)
    with, when ``original`` is among the runs, the change of the time in shimmy (s) and the ratios of
    the peaks to those of ``original``."""

    profile: GroundProfile
    runs: dict[str, GroundRunResult]
    elapsed_s: float

    def table(self) -> list[dict[str, Any]]:
        """:func:`~shimmy.analyses.ground.summaries.comparison_table` of the runs."""
        return comparison_table({k: r.summary() for k, r in self.runs.items()})

    def to_dict(self, series_stride: int = 10, include_series: bool = True) -> dict[str, Any]:
        return comparison_dict(self.profile.to_dict(),
                               {k: r.to_dict(series_stride, include_series) for k, r in self.runs.items()},
                               self.elapsed_s)

    def summary_text(self) -> str:
        """The profile and the thresholds, then each run's lines
        (:func:`~shimmy.analyses.ground.summaries.comparison_summary`)."""
        return comparison_summary(self.to_dict(include_series=False))


def ground_runs(profile: Any, *, configs: Sequence[Configuration | str] = ALL_CONFIGURATIONS,
                params: Parameters | None = None, x0=None,
                options: GroundRunOptions | None = None, preset_options: dict[str, Any] | None = None,
                kick: Kick | dict[str, Any] | None = None, progress: Callable[[float, str], None] | None = None,
                **option_overrides) -> GroundRunComparison:
    """:func:`ground_run` of one profile for each configuration (``x0`` must suit every one, or be None), each with
    the same ``kick`` (if any)."""
    clock = time.perf_counter()
    profile, kick = _with_scenario(profile, kick)
    profile = as_profile(profile, preset_options)
    if kick is not None:
        kick_instant(kick, profile)  # refused before any run
    configs = [Configuration.parse(c) for c in configs]
    if not configs:
        raise InvalidParameterError("configs", [], "a non-empty list of configurations")
    report = progress or (lambda fraction, message: None)
    runs = {}
    for k, c in enumerate(configs):
        report(k / len(configs), f"ground run of {c.value}")
        runs[c.value] = ground_run(c, profile, params=params, x0=x0, options=options, kick=kick,
                                   **option_overrides)
    report(1.0, "done")
    return GroundRunComparison(profile, runs, time.perf_counter() - clock)
