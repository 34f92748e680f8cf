"""Time histories at one operating point: :func:`simulate` and its result.

Accuracy: the default tolerances (rtol 1e-7, atol 1e-10) are chosen so that tightening
both tenfold changes the steady amplitudes by well under 0.5 % (a test keeps this),
and the result agrees with scipy's LSODA at rtol 1e-8 to the same level (the benchmark
prints the comparison).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...version import __version__
from ...model import integrator
from ...model.configurations import STATE_NAMES, Configuration
from ...model.equations import build_model
from ...errors import InvalidParameterError
from ...model.parameters import DEFAULT_PSI0, Parameters, check_number, check_operating_point
from . import nes_range
from .summaries import simulation_summary
from .response import (DECAYED_FRACTION, ResponseType, classify_run, dominant_frequency, peak_amplitude,
                       power_spectra)

#: Largest simulated time and the densest output accepted (service limits build on these).
MAX_T_END = 3600.0
MAX_SAMPLES = 5_000_000

#: What each integrator status means, as a result's message (ground runs use the same).
STATUS_MESSAGES = {
    integrator.SUCCESS: "integration finished",
    integrator.MAX_STEPS: "step budget exhausted before t_end (max_steps); the result is truncated",
    integrator.NES_OUT_OF_RANGE: ("the NES relative rotation |psi - psis| reached pi/6, where the exact "
                                  "roller geometry is undefined; the result is truncated"),
    integrator.NOT_FINITE: "the state became non-finite (the response diverged); the result is truncated",
    integrator.STEP_TOO_SMALL: "the step size fell below 1e-14 t; the result is truncated",
}


@dataclass(frozen=True)
class SimulationOptions:
    """Numerical settings of a time history (validated at construction)."""

    t_end: float = 60.0
    dt_out: float = 0.001
    rtol: float = 1e-7
    atol: float = 1e-10
    window: float = 20.0
    max_steps: int = 10_000_000
    exact_nes: bool = False

    def __post_init__(self):
        object.__setattr__(self, "t_end", check_number("t_end", self.t_end, 0.1, MAX_T_END, "s"))
        object.__setattr__(self, "dt_out", check_number("dt_out", self.dt_out, 1e-5, 0.01, "s"))
        object.__setattr__(self, "rtol", check_number("rtol", self.rtol, 1e-13, 1e-3))
        object.__setattr__(self, "atol", check_number("atol", self.atol, 1e-16, 1e-3))
        object.__setattr__(self, "window", check_number("window", self.window, 0.05, MAX_T_END, "s"))
        object.__setattr__(self, "max_steps", int(check_number("max_steps", self.max_steps, 1, 1e9,
                                                                integer=True)))
        if not isinstance(self.exact_nes, bool):
            raise InvalidParameterError("exact_nes", self.exact_nes, "true or false", "is not a boolean")
        samples = int(round(self.t_end / self.dt_out)) + 1
        if samples > MAX_SAMPLES:
            raise InvalidParameterError("t_end", self.t_end, f"t_end/dt_out <= {MAX_SAMPLES}",
                                        "asks for too many output samples")

    @property
    def steady_window(self) -> float:
        """The window actually used: at most a third of the run."""
        return min(self.window, self.t_end / 3.0)

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass(frozen=True)
class SimulationResult:
    """A time history with its steady-state measures and how the integration went."""

    config: Configuration
    V: float
    Fz: float
    params: Parameters
    options: SimulationOptions
    t: np.ndarray
    states: np.ndarray  # (n_states, n_samples)
    amplitude: dict[str, float]
    frequency_hz: float
    response_type: ResponseType
    steady: bool
    success: bool
    status: int
    message: str
    counters: dict[str, int] = field(default_factory=dict)
    elapsed_s: float = 0.0
    warnings: list[str] = field(default_factory=list)

    def state(self, name: str) -> np.ndarray:
        return self.states[STATE_NAMES.index(name)]

    @property
    def lateral(self) -> np.ndarray:
        """Lateral bending displacement l_g * delta (m)."""
        return self.params.gear.l_g * self.states[2]

    def to_dict(self, include_series: bool = False) -> dict[str, Any]:
        out = {
            "config": self.config.value, "V": self.V, "Fz": self.Fz,
            "amplitude": dict(self.amplitude),
            "frequency_hz": _json_float(self.frequency_hz),
            "response_type": self.response_type.value, "steady": self.steady,
            "success": self.success, "message": self.message,
            "counters": dict(self.counters), "options": self.options.to_dict(),
            "params": self.params.to_dict(), "warnings": list(self.warnings), "version": __version__,
        }
        if include_series:
            out["series"] = self.series()
        return out

    def series(self) -> dict[str, list[float]]:
        cols = {"t": self.t}
        for i, name in enumerate(STATE_NAMES[:self.states.shape[0]]):
            cols[name] = self.states[i]
        cols["lateral"] = self.lateral
        return {k: v.tolist() for k, v in cols.items()}

    def spectrum(self, f_max: float = 60.0) -> dict[str, Any]:
        """Power spectra of psi and l_g delta over the steady window up to ``f_max`` (Hz), for plots, with
        the dominant frequency (Hz; None where there is none)."""
        dt = self.options.dt_out
        span = max(8, int(round(self.options.steady_window / dt)))
        spectra = power_spectra({"psi": self.states[0, -span:], "lateral": self.lateral[-span:]}, dt, f_max)
        return {**spectra, "dominant_hz": _json_float(self.frequency_hz)}

    def write_csv(self, path) -> None:
        names = ["t", *STATE_NAMES[:self.states.shape[0]], "lateral"]
        data = np.column_stack([self.t, self.states.T, self.lateral])
        np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g")

    def summary_text(self) -> str:
        """The short table ``python -m shimmy simulate`` prints
        (:func:`~shimmy.analyses.core.summaries.simulation_summary`)."""
        return simulation_summary(self.to_dict())


def _json_float(x: float):
    return None if not np.isfinite(x) else float(x)


def simulate(config: Configuration | str, V: float, Fz: float, *, params: Parameters | None = None,
             t_end: float | None = None, x0=None, options: SimulationOptions | None = None,
             frequency: bool = True, **option_overrides) -> SimulationResult:
    """Integrate the model at forward speed V (m/s) and vertical load Fz (N).

    ``x0`` defaults to psi = 0.001 rad with all else zero (the study's start). Options may be
    given as a :class:`SimulationOptions` or as keyword overrides (``rtol=...``).
    Integration failures (divergence, step budget, NES out of range) do not raise:
    the result has ``success=False``, a ``message`` and the part that was computed.
    ``frequency=False`` skips the spectrum (``frequency_hz`` is then NaN): for callers that need
    only the settled state, such as the seeds of a bifurcation diagram.
    """
    config = Configuration.parse(config)
    V, Fz = check_operating_point(V, Fz)
    params = params if params is not None else Parameters()
    if options is None:
        options = SimulationOptions()
    if t_end is not None:
        option_overrides["t_end"] = t_end
    if option_overrides:
        options = SimulationOptions(**{**options.to_dict(), **option_overrides})
    model = build_model(config, params, exact_nes=options.exact_nes)
    n = model.n_states
    start = initial_state(x0, n)

    n_out = int(round(options.t_end / options.dt_out)) + 1
    out = np.empty((n_out, integrator.N_FULL))
    clock = time.perf_counter()
    status, accepted, rejected, calls, written = integrator.integrate(
        start, options.t_end, options.dt_out, V, Fz, model.coefficients, *model.flags,
        options.rtol, options.atol, options.max_steps, out)
    elapsed = time.perf_counter() - clock

    t = np.arange(written) * options.dt_out
    states = np.ascontiguousarray(out[:written, :n].T)
    measures = _steady_measures(states, start[:n], params, options, frequency)
    beyond = nes_range.warning(config, params, nes_range.rotation_peak(states), options.exact_nes)
    return SimulationResult(
        config=config, V=V, Fz=Fz, params=params, options=options, t=t, states=states,
        success=status == integrator.SUCCESS, status=int(status), message=STATUS_MESSAGES[status],
        counters={"steps": int(accepted), "rejected": int(rejected), "rhs_calls": int(calls)},
        elapsed_s=elapsed, warnings=[beyond] if beyond else [], **measures)


def kicked_state(config: Configuration | str, params: Parameters, psi0: float = DEFAULT_PSI0,
                 lateral0: float = 0.0) -> np.ndarray:
    """A start from straight rolling with torsion ``psi0`` (rad) and lateral bending displacement
    l_g delta = ``lateral0`` (m), the rest at rest: the ``x0`` of :func:`simulate` (the API's and the
    command line's ``psi0`` and ``lateral0``)."""
    x0 = np.zeros(Configuration.parse(config).n_states)
    x0[0], x0[2] = psi0, lateral0 / params.gear.l_g
    return x0


def initial_state(x0, n: int) -> np.ndarray:
    """The integrator's full start vector from ``x0`` (n numbers; None: psi = 0.001 rad, all else zero)."""
    start = np.zeros(integrator.N_FULL)
    if x0 is None:
        start[0] = DEFAULT_PSI0
        return start
    x0 = np.asarray(x0, dtype=float)
    if x0.shape != (n,):
        raise InvalidParameterError("x0", x0.tolist(), f"{n} numbers ({', '.join(STATE_NAMES[:n])})",
                                    "has the wrong length")
    if not np.all(np.isfinite(x0)):
        raise InvalidParameterError("x0", x0.tolist(), "finite numbers", "is not finite")
    start[:n] = x0
    return start


def _steady_measures(states: np.ndarray, x0: np.ndarray, params: Parameters,
                     options: SimulationOptions, frequency: bool = True) -> dict[str, Any]:
    dt = options.dt_out
    k_psi, k_delta, l_g = params.gear.k_psi, params.gear.k_delta, params.gear.l_g
    span = max(2, int(round(options.steady_window / dt)))
    if states.shape[1] < 2 * span:  # truncated run: measure what there is
        span = max(1, states.shape[1] // 2)
    final = states[:, -span:]
    previous = states[:, -2 * span:-span] if states.shape[1] >= 2 * span else final

    def energies(block):
        psi_amp, delta_amp = peak_amplitude(block[0]), peak_amplitude(block[2])
        return psi_amp, delta_amp, 0.5 * k_psi * psi_amp ** 2, 0.5 * k_delta * delta_amp ** 2

    psi_amp, delta_amp, e_t, e_l = energies(final)
    _, _, e_t_prev, e_l_prev = energies(previous)
    # the start's energy: elastic and kinetic (a start kicked in a rate only, as a margin's along dpsi, has energy)
    e_initial = (0.5 * k_psi * x0[0] ** 2 + 0.5 * k_delta * x0[2] ** 2
                 + 0.5 * params.gear.Iz * x0[1] ** 2 + 0.5 * params.gear.Ix * x0[3] ** 2)
    if e_initial == 0.0:
        e_initial = np.inf  # at rest in torsion and bending at start: judge by decay alone
    response = classify_run(e_initial, e_t, e_l, e_t_prev + e_l_prev)
    amplitude = {"psi": psi_amp, "lateral": l_g * delta_amp, "lam": peak_amplitude(final[4])}
    if states.shape[0] == 7:
        amplitude["psis"] = peak_amplitude(final[5])
        amplitude["nes_relative"] = peak_amplitude(final[0] - final[5])
    total, total_prev = np.sqrt(e_t + e_l), np.sqrt(e_t_prev + e_l_prev)
    hz = float("nan")
    if response is ResponseType.STABLE:
        # Settled when the motion has decayed to 1e-3 of its start.
        steady = bool(total <= DECAYED_FRACTION * np.sqrt(e_initial))
    else:
        # Settled when the amplitude changed by less than 1 % against the previous window.
        steady = bool(total_prev > 0 and abs(total / total_prev - 1.0) < 0.01)
        if frequency:
            hz = dominant_frequency([np.sqrt(k_psi) * final[0], np.sqrt(k_delta) * final[2]], dt)
    return {"amplitude": amplitude, "frequency_hz": hz, "response_type": response,
            "steady": steady}
