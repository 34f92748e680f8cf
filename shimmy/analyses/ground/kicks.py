"""A disturbance during a ground run: a yaw kick at a chosen time or speed, and whether shimmy starts after it.

A runway joint or a touchdown with yaw is a short disturbance of the nose wheel's torsion. A
:class:`Kick` is a jump of one component of the state at one instant: the yaw angle psi by
``size`` rad (``kind="psi"``) or the yaw rate dpsi by ``size`` rad/s (``kind="dpsi"``), the rest
of the state (lateral bending, the absorbers) as it is, added to the state the run has reached
there. The instant is given either as a time on the profile's clock (``at_time``, s) or as a speed
(``at_speed``, m/s): the first time the profile's speed V(t), linear between its rows, equals it
(:func:`kick_instant`). :func:`shimmy.ground_run` splits the
integration at that instant and applies the jump there (not at the nearest output sample).

**Whether shimmy starts** (:func:`kick_outcome`): beside the kicked run, the same run from the same
state at the kick without the jump. From the kick on, both are cut into windows of ``WINDOW``
(1 s, as the margins' runs: more than six periods of the slowest shimmy mode), each with its
largest |psi| and |delta| as the vector e = (sqrt(k_psi) psi, sqrt(k_delta) delta) (the elastic
energies' square roots, the margins' measure: torsion and bending on one scale). Window by window
after the first:

* the kicked run is **back on the run without the kick** in a window when its e is within
  ``MATCH_TOL`` (10 %, the margins' match) of that run's, or when both are below the shimmy
  thresholds and the kicked one is falling (by ``1 - DECAY_RATIO``, 1 %, or more against the
  window before, the margins' decay); two such windows in a row: the kick's disturbance has died
  out, **no shimmy started** (mode ``none``);
* the kicked run is above a threshold (|psi| or |l_g delta| beyond the run's shimmy thresholds),
  not back on the other, not closing in on it (their distance not 1 % or more below the window
  before), not in shimmy of the mode the other is in, and within 10 % of its window before
  (settled, as a margins' run on an attractor), ``HOLD`` (3) windows in a row (a run lingering for
  a second or two near the cycle between two basins and then leaving is no start):
  **shimmy started**, in the mode of the last of them (torsional, lateral or both:
  :func:`~shimmy.analyses.core.response.mode_of` of the torsional energy share, the classification
  of the margins' attractors), with the largest amplitudes of the stretch above the thresholds
  that follows; the run without the kick is described beside (in shimmy or not, its mode), so
  that a kick that switches lateral shimmy to torsional shimmy reads as such;
* otherwise (a transient still settling) the next window decides. A run that ends before either
  is **undecided**, and says so.

Whether the run was in shimmy in the second before the kick is reported beside, and how much longer
the kicked run is in shimmy from the kick on than the run without it (``extra_time_in_shimmy_s``:
a kick that only brings forward a shimmy the gear would have anyway reads as no shimmy started,
with the time it adds).

:data:`KICK_PRESETS` are two documented scenarios: a runway joint on the take-off and a touchdown
with yaw on the landing roll.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import InvalidParameterError
from ...model.parameters import V_RANGE, check_number, unknown_name_error
from ..core.response import mode_of, torsional_share
from .ground_profiles import GroundProfile

#: The kicked component: its index in the state, its unit, the largest |size| and what it is.
KINDS = {"psi": (0, "rad", 0.5, "yaw angle"), "dpsi": (1, "rad/s", 50.0, "yaw rate")}
#: The request fields of a kick (the names its refusals give).
FIELDS = ("kick", "kick_size", "kick_at_time", "kick_at_speed")
#: The clock of a table may start anywhere (as :func:`~shimmy.analyses.ground.ground_profiles.profile_from_table`).
TIME_LIMIT = 1e5  # s
WINDOW = 1.0  # s: the windows in which the outcome is judged (as the margins' runs)
DECAY_RATIO = 0.99  # a window 1 % or more below the one before is falling (as the margins' runs)
MATCH_TOL = 0.1  # a window within 10 % of the run without the kick is on it (as the margins' attractors)
HOLD = 3  # windows in a row apart from the run without the kick and settled: shimmy started (not a passing transient)
SAME_INSTANT = 1e-9  # s: closer than this to an output sample, the kick is at that sample

METHOD = (f"beside the kicked run, the run without the kick from the same state; windows of {WINDOW:g} s from the "
          f"kick, each its largest |psi| and |delta| as e = (sqrt(k_psi) psi, sqrt(k_delta) delta): no shimmy "
          f"started at the second window in a row back on the run without the kick (e within {100 * MATCH_TOL:g} % "
          f"of it, or both below the thresholds and falling by {100 * (1 - DECAY_RATIO):g} % or more); shimmy "
          f"started at the third window in a row above a threshold, apart from that run, not closing in on it, not "
          f"in shimmy of its mode and within {100 * MATCH_TOL:g} % of the window before, in the mode of that window")

#: Scenarios: a profile preset with a kick (the workbench's and the command line's named kicks).
KICK_PRESETS: dict[str, dict[str, Any]] = {
    "runway_joint": {
        "label": "Runway joint (take-off, yaw-rate kick at 60 m/s)", "preset": "takeoff",
        "kick": {"kick": "dpsi", "kick_size": 1.0, "kick_at_speed": 60.0},
        "description": "the take-off preset; at 60 m/s a runway joint kicks the wheel's yaw rate by 1 rad/s (a "
                       "yaw of about 0.016 rad at the torsion's 9.8 Hz: of the order of the smallest yaw kick that "
                       "starts torsional shimmy of `original` at 50 m/s, 550 kN)"},
    "touchdown_yaw": {
        "label": "Touchdown with yaw (landing roll, 0.05 rad at t = 0)", "preset": "landing",
        "kick": {"kick": "psi", "kick_size": 0.05, "kick_at_time": 0.0},
        "description": "the landing-roll preset; the nose wheel touches down yawed by 0.05 rad (2.9 degrees) "
                       "against the strut's straight-rolling position"},
}


@dataclass(frozen=True)
class Kick:
    """A jump of psi (rad) or dpsi (rad/s) by ``size`` at ``at_time`` (s, the profile's clock) or at ``at_speed``
    (m/s): exactly one of the two. Checked at construction; refusals name the request's fields."""

    kind: str
    size: float
    at_time: float | None = None
    at_speed: float | None = None

    def __post_init__(self):
        if self.kind not in KINDS:
            raise unknown_name_error(str(self.kind), KINDS, "kick")
        _, unit, largest, what = KINDS[self.kind]
        object.__setattr__(self, "size", check_number("kick_size", self.size, -largest, largest,
                                                      f"{unit} (a kick in {self.kind}, the {what})"))
        if (self.at_time is None) == (self.at_speed is None):
            given = "both kick_at_time and kick_at_speed" if self.at_time is not None else "neither"
            raise InvalidParameterError("kick_at_time", self.at_time,
                                        "exactly one of kick_at_time (s) and kick_at_speed (m/s)",
                                        message=f"a kick is at a time or at a speed: {given} given; allowed: exactly "
                                                "one of kick_at_time (s) and kick_at_speed (m/s)")
        if self.at_time is not None:
            object.__setattr__(self, "at_time", check_number("kick_at_time", self.at_time, -TIME_LIMIT, TIME_LIMIT,
                                                             "s"))
        else:
            object.__setattr__(self, "at_speed", check_number("kick_at_speed", self.at_speed, *V_RANGE, "m/s"))

    @classmethod
    def of(cls, fields: dict[str, Any]) -> "Kick | None":
        """The kick of a request's fields ``kick``, ``kick_size``, ``kick_at_time``, ``kick_at_speed`` (None: no
        kick; then none of the others may be given)."""
        if fields.get("kick") is None:
            given = [f for f in FIELDS[1:] if fields.get(f) is not None]
            if given:
                value = fields[given[0]]
                shown = f"{value:g}" if isinstance(value, (int, float)) and not isinstance(value, bool) else repr(value)
                raise InvalidParameterError(given[0], value, "only with kick (psi or dpsi)",
                                            message=f"{given[0]}={shown} is given without a kick; allowed: only with "
                                                    "kick = psi or dpsi")
            return None
        if fields.get("kick_size") is None:
            _, unit, largest, what = KINDS.get(fields["kick"], (0, "", 0.0, ""))
            allowed = f"a number in [{-largest:g}, {largest:g}] {unit}" if unit else "a number"
            raise InvalidParameterError("kick_size", None, allowed,
                                        message=f"kick_size is required with a kick; allowed: {allowed}")
        return cls(fields["kick"], fields["kick_size"], fields.get("kick_at_time"), fields.get("kick_at_speed"))

    @property
    def index(self) -> int:
        return KINDS[self.kind][0]

    @property
    def unit(self) -> str:
        return KINDS[self.kind][1]

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "size": self.size, "unit": self.unit, "at_time": self.at_time,
                "at_speed": self.at_speed}

    def describe(self) -> str:
        where = f"t = {self.at_time:g} s" if self.at_time is not None else f"V = {self.at_speed:g} m/s"
        return f"{self.kind} {self.size:+g} {self.unit} at {where}"


def kick_instant(kick: Kick, profile: GroundProfile) -> float:
    """The time (s, the profile's clock) of the kick: ``at_time`` within the run, or the first time V(t) (linear
    between the rows) equals ``at_speed``. Refused, naming the field, when the run does not contain it."""
    t0, t1 = float(profile.t[0]), float(profile.t[-1])
    if kick.at_time is not None:
        if not t0 <= kick.at_time < t1:
            allowed = f"a time within the run: [{t0:g}, {t1:g}) s"
            raise InvalidParameterError("kick_at_time", kick.at_time, allowed,
                                        message=f"kick_at_time={kick.at_time:g} s is outside the {profile.name} "
                                                f"profile's run; allowed: {allowed}")
        return kick.at_time
    s = kick.at_speed
    V, t = profile.V, profile.t
    low, high = float(V.min()), float(V.max())
    if not low <= s <= high:
        allowed = f"a speed the run reaches: [{low:g}, {high:g}] m/s"
        raise InvalidParameterError("kick_at_speed", s, allowed,
                                    message=f"kick_at_speed={s:g} m/s is never reached by the {profile.name} profile; "
                                            f"allowed: {allowed}")
    found = next(float(t[j]) if float(V[j]) == s else float(t[j] + (s - V[j]) / (V[j + 1] - V[j]) * (t[j + 1] - t[j]))
                 for j in range(V.size - 1) if min(V[j], V[j + 1]) <= s <= max(V[j], V[j + 1]))
    if found >= t1:  # reached only at the very end: no run after it
        raise InvalidParameterError("kick_at_speed", s, "a speed the run reaches before its end",
                                    message=f"kick_at_speed={s:g} m/s is reached by the {profile.name} profile only at "
                                            f"its last row (t = {t1:g} s); allowed: a speed the run reaches before "
                                            "its end")
    return found


def _windows(t: np.ndarray, psi: np.ndarray, delta: np.ndarray, t_kick: float) -> list[tuple[float, float, float]]:
    """(end time, max |psi|, max |delta|) of each whole window of WINDOW s from the kick on (as far as the
    arrays, which may be shorter than ``t``, reach)."""
    out = []
    start = int(np.searchsorted(t, t_kick - SAME_INSTANT))
    size = min(t.size, psi.size)
    k = 0
    while True:
        end = t_kick + (k + 1) * WINDOW
        if size == 0 or end > t[size - 1] + SAME_INSTANT:
            return out
        stop = int(np.searchsorted(t, end - SAME_INSTANT))
        if stop <= start:
            return out
        out.append((end, float(np.abs(psi[start:stop]).max()), float(np.abs(delta[start:stop]).max())))
        start, k = stop, k + 1


def kick_outcome(kick: Kick, t_kick: float, before: np.ndarray, after: np.ndarray, t: np.ndarray, V: np.ndarray,
                 Fz: np.ndarray, states: np.ndarray, without: np.ndarray, *, k_psi: float, k_delta: float, l_g: float,
                 psi_threshold: float, lateral_threshold: float) -> dict[str, Any]:
    """What the kick at ``t_kick`` (the state ``before`` and ``after`` the jump) did to the run (``states``, on the
    samples ``t``), against the same run without it (``without``: the states from the same state at the kick
    without the jump, as far as that run got). Module docstring."""
    V_k, Fz_k = (float(np.interp(t_kick, t, x)) if t.size else math.nan for x in (V, Fz))
    lead = (t >= t_kick - WINDOW - SAME_INSTANT) & (t < t_kick - SAME_INSTANT)
    already = bool(lead.any() and (np.abs(states[0, lead]).max() > psi_threshold
                                   or l_g * np.abs(states[2, lead]).max() > lateral_threshold))
    out: dict[str, Any] = {
        **kick.to_dict(), "t": t_kick, "V": V_k, "Fz": Fz_k,
        "state_before": {"psi": float(before[0]), "dpsi": float(before[1])},
        "state_after": {"psi": float(after[0]), "dpsi": float(after[1])},
        "in_shimmy_before": already, "shimmy_started": None, "mode": None, "t_judged": None, "V_judged": None,
        "amplitude": None, "peak": None, "without_kick": None, "method": METHOD}
    kicked = _windows(t, states[0], states[2], t_kick)
    plain = _windows(t, without[0], without[2], t_kick)

    def vector(w) -> np.ndarray:
        return np.array([math.sqrt(k_psi) * w[1], math.sqrt(k_delta) * w[2]])

    def above(w) -> bool:
        return w[1] > psi_threshold or l_g * w[2] > lateral_threshold

    def mode(w) -> str:
        return str(mode_of(float(torsional_share(w[1], w[2], k_psi, k_delta)))) if above(w) else "none"

    def judged(k: int) -> dict[str, Any]:
        w, b = kicked[k], plain[k]
        return {"t_judged": w[0], "V_judged": float(np.interp(w[0], t, V)),
                "without_kick": {"in_shimmy": above(b), "mode": mode(b),
                                 "amplitude": {"psi": b[1], "lateral": l_g * b[2]}}}

    back, hold = [False], 0
    for k in range(1, min(len(kicked), len(plain))):
        w, previous = kicked[k], kicked[k - 1]
        gap, gap_before = (float(np.linalg.norm(vector(x) - vector(y))) for x, y in ((w, plain[k]),
                                                                                    (previous, plain[k - 1])))
        falling = np.linalg.norm(vector(w)) < DECAY_RATIO * np.linalg.norm(vector(previous))
        back.append(gap <= MATCH_TOL * float(np.linalg.norm(vector(plain[k]))) or (falling and not above(w)
                                                                                    and not above(plain[k])))
        other = judged(k)["without_kick"]  # the run without the kick in shimmy of the kicked run's mode: not apart
        same_shimmy = other["in_shimmy"] and other["mode"] == mode(w)
        settled = float(np.linalg.norm(vector(w) - vector(previous))) <= MATCH_TOL * float(np.linalg.norm(vector(w)))
        apart = above(w) and not back[-1] and gap >= DECAY_RATIO * gap_before and not same_shimmy
        hold = hold + 1 if apart and settled else 0
        if back[-1] and back[-2]:
            out.update(shimmy_started=False, mode="none", **judged(k))
            return out
        if hold >= HOLD:
            stretch = [w]
            for later in kicked[k + 1:]:
                if not above(later):
                    break
                stretch.append(later)
            peak = max(stretch, key=lambda x: float(np.linalg.norm(vector(x))))
            out.update(shimmy_started=True, mode=mode(w), **judged(k),
                       amplitude={"psi": w[1], "lateral": l_g * w[2]},
                       peak={"psi": peak[1], "lateral": l_g * peak[2], "t": peak[0]})
            return out
    left = float(t[-1]) - t_kick if t.size else 0.0
    out["note"] = (f"undecided: the run ends {left:.3g} s after the kick, before its windows of {WINDOW:g} s show it "
                   "holding apart from the run without it or back on that run")
    return out


def outcome_text(outcome: dict[str, Any] | None) -> str:
    """One line on a kick's outcome, for tables and the command line's summary."""
    if outcome is None:
        return "no kick"
    if not outcome.get("applied", True):
        return "not applied (the integration stopped before it)"
    if outcome["shimmy_started"] is None:
        return "undecided (the run ends first)"
    other = outcome["without_kick"]
    plain = f"{other['mode']} shimmy" if other["in_shimmy"] else "no shimmy"
    extra = outcome.get("extra_time_in_shimmy_s")
    added = "" if extra is None else f"; {extra:+.3g} s in shimmy against the run without it"
    if not outcome["shimmy_started"]:
        return (f"no shimmy started: back on the run without it by t = {outcome['t_judged']:.4g} s ({plain} there)"
                + added)
    return (f"{outcome['mode']} shimmy by t = {outcome['t_judged']:.4g} s ({outcome['V_judged']:.4g} m/s), |psi| up "
            f"to {outcome['peak']['psi']:.3g} rad (without the kick: {plain}){added}")


def scenario(name: str, fields: dict[str, Any] | None = None) -> tuple[str, dict[str, Any]]:
    """The profile preset and the kick fields of the scenario ``name`` (:data:`KICK_PRESETS`), with ``fields``
    (kick, kick_size, kick_at_time, kick_at_speed) given for it taking the place of the scenario's: the kind and
    the size each, the instant as a whole (a time given replaces the scenario's speed)."""
    given = {k: v for k, v in (fields or {}).items() if k in FIELDS and v is not None}
    kick = dict.fromkeys(FIELDS) | KICK_PRESETS[name]["kick"]
    if "kick_at_time" in given or "kick_at_speed" in given:
        kick["kick_at_time"] = kick["kick_at_speed"] = None
    return KICK_PRESETS[name]["preset"], kick | given
