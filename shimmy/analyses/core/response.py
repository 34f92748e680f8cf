"""Measures of a sampled response: amplitudes, dominant frequency, response type.

Criteria (documented here because every caller shares them):

* Steady window: the last ``window`` seconds of the run; the ``window`` before it is
  the previous window, used to judge whether the response has settled.
* Amplitude: max |x| over the steady window, refined by a parabola through the largest
  sample and its neighbours (sampling error O(dt^2) -> O(dt^4)).
* Modal energies: E_t = k_psi psi_amp^2 / 2 (torsion), E_l = k_delta delta_amp^2 / 2
  (lateral bending); torsional and lateral amplitudes are in different units, the
  elastic energies put them on one scale.
* Mode of a limit cycle (:func:`mode_of`): torsional share s >= 0.8 torsional,
  s <= 0.2 lateral, both in between (the same thresholds as the response type).
* Response type of one run:
    - ``Stable`` if the motion decays: sqrt(E_t + E_l) over the steady window is below
      1e-3 of its initial value, or it is smaller than its initial value and still
      falling (by more than 1 % against the previous window);
    - otherwise, with torsional share s = E_t / (E_t + E_l): ``Torsion`` if s >= 0.8,
      ``Lateral`` if s <= 0.2, ``Both`` in between.
* Dominant frequency: the peak of the summed power spectra of sqrt(k_psi) psi and
  sqrt(k_delta) delta over the steady window (Hann window, mean removed, 8x zero
  padding), refined by a parabola through the log power at the peak bin and its
  neighbours. For a pure tone the error is well below 0.01 Hz with a 20 s window.
"""

from __future__ import annotations

from enum import StrEnum

import numpy as np


class ResponseType(StrEnum):
    STABLE = "Stable"
    TORSION = "Torsion"
    LATERAL = "Lateral"
    BOTH = "Both"


TORSION_SHARE = 0.8
LATERAL_SHARE = 0.2
DECAY_RATIO = 0.99
DECAYED_FRACTION = 1e-3


def peak_amplitude(signal: np.ndarray) -> float:
    """max |signal|, refined by a parabola through the largest sample and its neighbours."""
    a = np.abs(np.asarray(signal, dtype=float))
    i = int(np.argmax(a))
    if 0 < i < a.size - 1:
        y0, y1, y2 = a[i - 1], a[i], a[i + 1]
        denom = y0 - 2.0 * y1 + y2
        if denom < 0.0:
            return float(y1 - 0.125 * (y2 - y0) ** 2 / denom)
    return float(a[i])


def windowed_power(signal: np.ndarray, window: np.ndarray, n_fft: int | None = None) -> np.ndarray:
    """|FFT|^2 of the signal with its mean removed, times ``window``, zero-padded to ``n_fft`` samples."""
    signal = np.asarray(signal, dtype=float)
    return np.abs(np.fft.rfft((signal - signal.mean()) * window, n_fft)) ** 2


def power_spectra(signals: dict[str, np.ndarray], dt: float, f_max: float) -> dict[str, list[float]]:
    """Power spectra (Hann window, mean removed, no padding) of equally sampled signals up to ``f_max``
    (Hz), for plots: ``{"frequency_hz": [...], name: [...] for each signal}``."""
    n = next(iter(signals.values())).size
    window = np.hanning(n)
    freq = np.fft.rfftfreq(n, dt)
    keep = freq <= f_max
    return {"frequency_hz": freq[keep].tolist(), **{k: windowed_power(s, window)[keep].tolist()
                                                    for k, s in signals.items()}}


def dominant_frequency(signals: list[np.ndarray], dt: float) -> float:
    """Peak frequency (Hz) of the summed power spectra of equally sampled signals."""
    n = signals[0].size
    if n < 8:
        return float("nan")
    window = np.hanning(n)
    n_fft = 8 * int(2 ** np.ceil(np.log2(n)))
    power = np.zeros(n_fft // 2 + 1)
    for s in signals:
        power += windowed_power(s, window, n_fft)
    k = int(np.argmax(power[1:])) + 1
    if power[k] <= 0.0:
        return float("nan")
    offset = 0.0
    if k < power.size - 1:
        l0, l1, l2 = np.log(power[k - 1:k + 2] + 1e-300)
        denom = l0 - 2.0 * l1 + l2
        if denom < 0.0:
            offset = 0.5 * (l0 - l2) / denom
    return float((k + offset) / (n_fft * dt))


class Mode(StrEnum):
    """Which motion dominates a limit cycle (same thresholds as the response type)."""

    TORSIONAL = "torsional"
    LATERAL = "lateral"
    BOTH = "both"


class ShimmyType(StrEnum):
    """The type of a point of a stability map, from its stable attractors (:func:`shimmy_type`)."""

    STABLE = "Stable"
    TORSION = "Torsion"
    LATERAL = "Lateral"
    BISTABLE = "Bistable"  # a torsional and a lateral cycle both stable
    BOTH = "Both"  # one cycle with both modes
    LATENT = "Latent"  # straight rolling stable, and a limit cycle stable beside it: a large enough kick starts shimmy


def shimmy_type(attractors: list[dict]) -> ShimmyType:
    """The map's type at a point from its stable attractors (``{"kind", "mode", ...}`` dicts): Latent where
    straight rolling is stable beside a stable limit cycle (whatever the cycle's mode), else by the cycles' modes."""
    modes = {a["mode"] for a in attractors if a["kind"] != "equilibrium"}
    if modes and any(a["kind"] == "equilibrium" for a in attractors):
        return ShimmyType.LATENT
    if Mode.TORSIONAL in modes and Mode.LATERAL in modes:
        return ShimmyType.BISTABLE
    if Mode.BOTH in modes:
        return ShimmyType.BOTH
    if Mode.TORSIONAL in modes:
        return ShimmyType.TORSION
    if Mode.LATERAL in modes:
        return ShimmyType.LATERAL
    return ShimmyType.STABLE


def dominant_mode(share: float) -> Mode:
    """Torsional or lateral, whichever holds the larger share of elastic energy (an eigenvector's)."""
    return Mode.TORSIONAL if share >= 0.5 else Mode.LATERAL


def torsional_share(psi_amp, delta_amp, k_psi: float, k_delta: float):
    """E_t / (E_t + E_l) with E_t = k_psi psi_amp^2 / 2, E_l = k_delta delta_amp^2 / 2 (array-safe)."""
    e_t = 0.5 * k_psi * np.square(psi_amp)
    e_l = 0.5 * k_delta * np.square(delta_amp)
    total = e_t + e_l
    return np.divide(e_t, total, out=np.full_like(np.asarray(total, float), np.nan), where=total > 0)


def mode_of(share: float) -> Mode:
    """Torsional if the torsional energy share is >= 0.8, lateral if <= 0.2, both in between."""
    if share >= TORSION_SHARE:
        return Mode.TORSIONAL
    if share <= LATERAL_SHARE:
        return Mode.LATERAL
    return Mode.BOTH


def classify_run(energy_initial: float, torsional_energy: float, lateral_energy: float,
                 previous_energy: float) -> ResponseType:
    """Response type of one run from modal energies (see the module docstring)."""
    total = torsional_energy + lateral_energy
    if total <= (DECAYED_FRACTION ** 2) * energy_initial:
        return ResponseType.STABLE
    if total < energy_initial and np.sqrt(total) < DECAY_RATIO * np.sqrt(previous_energy):
        return ResponseType.STABLE
    mode = mode_of(torsional_energy / total)
    return {Mode.TORSIONAL: ResponseType.TORSION, Mode.LATERAL: ResponseType.LATERAL}.get(mode, ResponseType.BOTH)
