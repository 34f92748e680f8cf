"""Ground-run profiles: forward speed V(t) and nose-gear load Fz(t) of a take-off, a landing roll or a taxi.

A profile is a table of (t, V, Fz) points (s, m/s, N), linearly interpolated between them; the
run goes from the first time to the last. :func:`profile_from_table` checks a table given by a
user and names the row and the column of the first problem; :func:`preset` builds one of three
documented presets from adjustable settings (each a frozen dataclass with ranges, like the model
parameters), sampled every ``dt_table`` seconds.

The presets are deliberately simple kinematics, each assumption stated on its settings class:

* **take-off** (:class:`TakeoffSettings`): constant acceleration from taxi speed to rotation
  speed; the nose-gear load falls from its static value as wing lift builds with V^2, to the
  load left at nose lift-off (rotation), where the run ends.
* **landing roll** (:class:`LandingSettings`): nose-gear touchdown at a given speed with most of
  the weight still on the wing; over the lift-dump time the spoilers dump a share of the lift and
  the brakes come on, transferring load forward; constant deceleration to taxi speed.
* **taxi** (:class:`TaxiSettings`): accelerate gently to taxi speed, hold it, slow down; the load
  is the static one, optionally with a slow sinusoidal variation (uneven surface, turns).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from ...errors import InvalidParameterError
from ...model.parameters import FZ_RANGE, V_RANGE, check_number, unknown_name_error

#: Largest number of table rows and the longest run (service limits build on these).
MAX_PROFILE_POINTS = 2000
MAX_DURATION = 3600.0  # s
MIN_DURATION = 0.1  # s
COLUMNS = (("t", "s"), ("V", "m/s"), ("Fz", "N"))


def _setting(default: float, low: float, high: float, unit: str, description: str):
    return field(default=default, metadata={"low": low, "high": high, "unit": unit, "description": description})


def _validate(obj) -> None:
    for f in dataclasses.fields(obj):
        m = f.metadata
        object.__setattr__(obj, f.name, check_number(f.name, getattr(obj, f.name), m["low"], m["high"], m["unit"]))


@dataclass(frozen=True)
class TakeoffSettings:
    """Take-off run: V = V_start + a t up to V_rotate; Fz = Fz_static - (Fz_static - Fz_rotate) (V/V_rotate)^2
    (lift grows with V^2 and carries the nose-gear load at rotation down to Fz_rotate, where the run ends at
    nose lift-off). Thrust pitching moment and the load transfer of the acceleration are neglected."""

    V_start: float = _setting(5.0, 1.0, 50.0, "m/s", "taxi speed at the start of the run")
    V_rotate: float = _setting(80.0, 20.0, 150.0, "m/s", "rotation speed (nose lift-off); the run ends there")
    acceleration: float = _setting(2.5, 0.3, 6.0, "m/s^2", "constant longitudinal acceleration")
    Fz_static: float = _setting(150e3, 20e3, 900e3, "N", "static nose-gear load")
    Fz_rotate: float = _setting(20e3, 10e3, 900e3, "N", "nose-gear load left at rotation")
    dt_table: float = _setting(0.5, 0.05, 5.0, "s", "time between the table points of the preset")

    def __post_init__(self):
        _validate(self)
        _above("V_rotate", self.V_rotate, "V_start", self.V_start, "m/s")
        _not_above("Fz_rotate", self.Fz_rotate, "Fz_static", self.Fz_static, "N")

    def table(self) -> np.ndarray:
        duration = (self.V_rotate - self.V_start) / self.acceleration
        t = _grid(duration, self.dt_table)
        V = np.minimum(self.V_start + self.acceleration * t, self.V_rotate)
        Fz = self.Fz_static - (self.Fz_static - self.Fz_rotate) * (V / self.V_rotate) ** 2
        return np.column_stack([t, V, Fz])


@dataclass(frozen=True)
class LandingSettings:
    """Landing roll from nose-gear touchdown: V = V_touchdown - a t down to V_taxi. With
    d(t) = min(t / t_dump, 1) (spoilers and brakes coming on) and lift share
    s(t) = (V/V_touchdown)^2 (1 - (1 - lift_retained) d(t)), the load is
    Fz = F - (F - Fz_touchdown) s(t) with F = Fz_static + brake_transfer d(t): Fz_touchdown at
    touchdown, rising as lift is dumped and braking moves load forward, to F at low speed."""

    V_touchdown: float = _setting(65.0, 20.0, 150.0, "m/s", "speed at nose-gear touchdown")
    V_taxi: float = _setting(8.0, 1.0, 30.0, "m/s", "speed at the end of the roll")
    deceleration: float = _setting(2.5, 0.3, 6.0, "m/s^2", "constant deceleration (brakes, reversers, drag)")
    Fz_touchdown: float = _setting(40e3, 10e3, 900e3, "N", "nose-gear load at touchdown")
    Fz_static: float = _setting(150e3, 20e3, 900e3, "N", "static nose-gear load")
    brake_transfer: float = _setting(50e3, 0.0, 400e3, "N", "load moved onto the nose gear by braking")
    t_dump: float = _setting(2.0, 0.1, 20.0, "s", "time for spoilers and brakes to come fully on")
    lift_retained: float = _setting(0.3, 0.0, 1.0, "", "share of the lift (at a given speed) left after lift dump")
    dt_table: float = _setting(0.5, 0.05, 5.0, "s", "time between the table points of the preset")

    def __post_init__(self):
        _validate(self)
        _above("V_touchdown", self.V_touchdown, "V_taxi", self.V_taxi, "m/s")
        _not_above("Fz_touchdown", self.Fz_touchdown, "Fz_static", self.Fz_static, "N")
        if self.Fz_static + self.brake_transfer > FZ_RANGE[1]:
            raise InvalidParameterError("brake_transfer", self.brake_transfer,
                                        f"a number in [0, {FZ_RANGE[1] - self.Fz_static:g}] N (Fz_static + "
                                        f"brake_transfer <= {FZ_RANGE[1]:g} N)")

    def table(self) -> np.ndarray:
        duration = (self.V_touchdown - self.V_taxi) / self.deceleration
        t = _grid(duration, self.dt_table)
        V = np.maximum(self.V_touchdown - self.deceleration * t, self.V_taxi)
        on = np.minimum(t / self.t_dump, 1.0)
        lift = (V / self.V_touchdown) ** 2 * (1.0 - (1.0 - self.lift_retained) * on)
        full = self.Fz_static + self.brake_transfer * on
        Fz = full - (full - self.Fz_touchdown) * lift
        return np.column_stack([t, V, Fz])


@dataclass(frozen=True)
class TaxiSettings:
    """Taxi: accelerate from V_start to V_taxi at a, hold, slow to V_end at the same rate, ending at
    `duration`; Fz = Fz_static (1 + load_variation sin(2 pi t / variation_period))."""

    V_start: float = _setting(2.0, 1.0, 30.0, "m/s", "speed at the start")
    V_taxi: float = _setting(10.0, 1.0, 30.0, "m/s", "taxi speed held")
    V_end: float = _setting(3.0, 1.0, 30.0, "m/s", "speed at the end")
    acceleration: float = _setting(0.5, 0.05, 3.0, "m/s^2", "rate of the speed changes")
    duration: float = _setting(60.0, 5.0, 600.0, "s", "length of the run")
    Fz_static: float = _setting(150e3, 20e3, 850e3, "N", "static nose-gear load")
    load_variation: float = _setting(0.0, 0.0, 0.3, "", "relative amplitude of a slow load variation")
    variation_period: float = _setting(5.0, 0.5, 60.0, "s", "period of that variation")
    dt_table: float = _setting(0.5, 0.05, 5.0, "s", "time between the table points of the preset")

    def __post_init__(self):
        _validate(self)
        up = abs(self.V_taxi - self.V_start) / self.acceleration
        down = abs(self.V_taxi - self.V_end) / self.acceleration
        if up + down > self.duration:
            raise InvalidParameterError("duration", self.duration, f"at least {up + down:g} s (the speed changes "
                                        f"at acceleration = {self.acceleration:g} m/s^2 take that long)")
        for name, f in (("load_variation", self.Fz_static * (1 - self.load_variation)),
                        ("load_variation", self.Fz_static * (1 + self.load_variation))):
            if not FZ_RANGE[0] <= f <= FZ_RANGE[1]:
                raise InvalidParameterError(name, self.load_variation, "a variation keeping Fz within "
                                            f"[{FZ_RANGE[0]:g}, {FZ_RANGE[1]:g}] N")

    def table(self) -> np.ndarray:
        up = abs(self.V_taxi - self.V_start) / self.acceleration
        down = abs(self.V_taxi - self.V_end) / self.acceleration
        t = np.union1d(_grid(self.duration, self.dt_table), [up, self.duration - down])
        V = np.interp(t, [0.0, up, self.duration - down, self.duration],
                      [self.V_start, self.V_taxi, self.V_taxi, self.V_end])
        Fz = self.Fz_static * (1.0 + self.load_variation * np.sin(2 * np.pi * t / self.variation_period))
        return np.column_stack([t, V, Fz])


PRESETS: dict[str, type] = {"takeoff": TakeoffSettings, "landing": LandingSettings, "taxi": TaxiSettings}


def _above(name: str, value: float, other: str, other_value: float, unit: str) -> None:
    if not value > other_value:
        raise InvalidParameterError(name, value, f"a number above {other} = {other_value:g} {unit}",
                                    f"must exceed {other}")


def _not_above(name: str, value: float, other: str, other_value: float, unit: str) -> None:
    if value > other_value:
        raise InvalidParameterError(name, value, f"a number up to {other} = {other_value:g} {unit}",
                                    f"must not exceed {other}")


def _grid(duration: float, dt: float) -> np.ndarray:
    """0, dt, 2 dt, ... (steps of exactly ``dt``, as the preset's setting says) and ``duration`` at the end: the
    last step is the rest, at most dt (a rest below dt/100 stretches the step before to at most 1.01 dt)."""
    n = max(1, int(math.floor(duration / dt + 1e-9)))
    t = dt * np.arange(n + 1, dtype=float)
    if duration - t[-1] > 1e-2 * dt:
        return np.append(t, duration)
    t[-1] = duration
    return t


@dataclass(frozen=True, eq=False)
class GroundProfile:
    """A checked (t, V, Fz) table: times strictly increasing, V and Fz within the model's ranges.

    ``name`` is the preset's name or "table"; ``settings`` the preset's settings (empty for a
    table) and ``assumptions`` the text that states what the preset assumes."""

    t: np.ndarray
    V: np.ndarray
    Fz: np.ndarray
    name: str = "table"
    settings: dict[str, float] = field(default_factory=dict)
    assumptions: str = ""

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def at(self, t) -> tuple[np.ndarray, np.ndarray]:
        """(V, Fz) at times ``t`` (s), linearly interpolated."""
        return np.interp(t, self.t, self.V), np.interp(t, self.t, self.Fz)

    def rows(self) -> list[list[float]]:
        return np.column_stack([self.t, self.V, self.Fz]).tolist()

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "settings": dict(self.settings), "assumptions": self.assumptions,
                "rows": self.rows(), "columns": [f"{c} ({u})" for c, u in COLUMNS]}


def profile_from_table(rows: Any, name: str = "table", settings: Mapping[str, float] | None = None,
                       assumptions: str = "") -> GroundProfile:
    """A checked profile from rows [t (s), V (m/s), Fz (N)] (a list of rows or an (n, 3) array).

    Refusals name the row and the column: field ``profile[i].V`` for row i (0-based, as in the
    JSON array), and the message gives the 1-based row number of the table as well."""
    if isinstance(rows, np.ndarray):
        rows = rows.tolist()
    if isinstance(rows, (str, bytes, Mapping)) or not isinstance(rows, Sequence):
        raise InvalidParameterError("profile", type(rows).__name__, "a list of rows [t (s), V (m/s), Fz (N)]",
                                    "is not a table")
    n = len(rows)
    if not 2 <= n <= MAX_PROFILE_POINTS:
        raise InvalidParameterError("profile", n, f"2 to {MAX_PROFILE_POINTS} rows [t, V, Fz]",
                                    message=f"profile has {n} row{'s' if n != 1 else ''}; allowed: 2 to "
                                    f"{MAX_PROFILE_POINTS} rows [t (s), V (m/s), Fz (N)]")
    table = np.empty((n, 3))
    limits = ((-1e5, 1e5), V_RANGE, FZ_RANGE)  # the clock may start anywhere; the duration is checked below
    for i, row in enumerate(rows):
        where = f"(row {i + 1} of the table)"
        if isinstance(row, (str, bytes, Mapping)) or not isinstance(row, Sequence) or len(row) != 3:
            size = len(row) if isinstance(row, Sequence) and not isinstance(row, (str, bytes)) else "not a row"
            raise InvalidParameterError(f"profile[{i}]", row, "3 numbers: t (s), V (m/s), Fz (N)",
                                        f"{where} has {size} columns" if isinstance(size, int) else f"{where} is "
                                        "not a row of numbers")
        for j, ((column, unit), (low, high)) in enumerate(zip(COLUMNS, limits, strict=True)):
            value = row[j]
            reason = None
            if isinstance(value, (str, bool)) or value is None:  # a JSON string is not a number, even "30"
                reason = "is not a number"
            else:
                try:
                    number = float(value)
                except OverflowError:  # an integer beyond float range
                    reason = "is not finite"
                except (TypeError, ValueError):
                    reason = "is not a number"
                else:
                    if not math.isfinite(number):
                        reason = "is not finite"
                    elif not low <= number <= high:
                        reason = "is out of range"
            if reason:
                raise InvalidParameterError(f"profile[{i}].{column}", value, f"a number in [{low:g}, {high:g}] {unit}",
                                            f"{where} {reason}")
            table[i, j] = number
        if i and not table[i, 0] > table[i - 1, 0]:
            raise InvalidParameterError(f"profile[{i}].t", rows[i][0],
                                        f"a time above the previous row's t = {table[i - 1, 0]:g} s",
                                        f"{where} does not increase")
    duration = table[-1, 0] - table[0, 0]
    if not MIN_DURATION <= duration <= MAX_DURATION:
        raise InvalidParameterError(f"profile[{n - 1}].t", rows[-1][0],
                                    f"a run of {MIN_DURATION:g} to {MAX_DURATION:g} s from t = {table[0, 0]:g} s",
                                    f"(row {n} of the table) makes the run {duration:g} s long")
    return GroundProfile(table[:, 0].copy(), table[:, 1].copy(), table[:, 2].copy(), name,
                         dict(settings or {}), assumptions)


def preset_settings(name: str, overrides: Mapping[str, Any] | None = None):
    """The settings object of preset ``name`` with ``overrides`` applied (each checked by name)."""
    if name not in PRESETS:
        raise unknown_name_error(name, list(PRESETS), "preset")
    cls = PRESETS[name]
    known = [f.name for f in dataclasses.fields(cls)]
    overrides = dict(overrides or {})
    for key in overrides:
        if key not in known:
            err = unknown_name_error(key, known, f"{name} setting")
            raise InvalidParameterError(f"preset_options.{key}", key, err.allowed, message=str(err))
    try:
        return cls(**overrides)
    except InvalidParameterError as exc:  # named as the request names it
        raise InvalidParameterError(f"preset_options.{exc.field}", exc.value, exc.allowed,
                                    message=f"{name} setting {exc}") from None


def preset(name: str, overrides: Mapping[str, Any] | None = None) -> GroundProfile:
    """The profile of preset ``name`` ("takeoff", "landing", "taxi") with adjusted settings."""
    settings = preset_settings(name, overrides)
    values = {f.name: getattr(settings, f.name) for f in dataclasses.fields(settings)}
    return profile_from_table(settings.table(), name, values, " ".join((type(settings).__doc__ or "").split()))


def preset_fields(name: str) -> list[dict[str, Any]]:
    """Each setting of a preset: name, default, range, unit, description (for forms and docs)."""
    if name not in PRESETS:
        raise unknown_name_error(name, list(PRESETS), "preset")
    return [{"name": f.name, "default": f.default, **f.metadata} for f in dataclasses.fields(PRESETS[name])]


def as_profile(profile: Any, overrides: Mapping[str, Any] | None = None) -> GroundProfile:
    """A :class:`GroundProfile` from a profile, a preset name (with ``overrides``) or a table of rows."""
    if isinstance(profile, GroundProfile):
        return profile
    if isinstance(profile, str):
        return preset(profile, overrides)
    if overrides:
        raise InvalidParameterError("preset_options", dict(overrides), "only with a preset profile",
                                    "given with a table")
    return profile_from_table(profile)
