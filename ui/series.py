"""Long time series made fit to draw."""

from __future__ import annotations

import math

import numpy as np

#: The time series are drawn as their envelope on this many time buckets (the lowest and highest
#: sample of each, in time order): a 60 s run at 2 ms is 30 001 samples a trace, a figure of
#: several MB to send and draw, while 2000 buckets are more than the plot's width in pixels.
#: The phase portrait and the downloads keep every sample.
ENVELOPE_BUCKETS = 2000


def envelope(t, y, buckets: int = ENVELOPE_BUCKETS) -> tuple[np.ndarray, np.ndarray]:
    """(t, y) thinned to the lowest and highest sample of each of ``buckets`` runs of samples, in
    time order (every sample where there are at most 2 ``buckets``): the drawn envelope is exact."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    if y.size <= 2 * buckets:
        return t, y
    per = math.ceil(y.size / buckets)
    padded = np.concatenate([y, np.full(per * buckets - y.size, y[-1])]).reshape(buckets, per)
    start = np.arange(buckets) * per
    keep = np.unique(np.minimum(np.concatenate([start + padded.argmin(axis=1), start + padded.argmax(axis=1)]),
                                y.size - 1))
    return t[keep], y[keep]


def band(t, y, buckets: int = ENVELOPE_BUCKETS, min_span: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, low, high): the lowest and highest sample of each of at most ``buckets`` runs of samples, each
    at least ``min_span`` long in time (a period and a bit, so that every run holds a whole cycle and
    the band spans the oscillation everywhere), at the run's middle time: drawn as a filled band (no
    line zig-zags between them, so no aliasing stripes on a fast oscillation); every sample (low = high)
    where runs would hold one sample."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    dt = (t[-1] - t[0]) / max(t.size - 1, 1) if t.size > 1 else 0.0
    per = max(math.ceil(y.size / buckets), math.ceil(min_span / dt) if dt > 0 else 1)
    if per <= 1:
        return t, y, y
    n = y.size // per * per
    blocks = y[:n].reshape(-1, per)
    mid = t[:n].reshape(-1, per).mean(axis=1)
    low, high = blocks.min(axis=1), blocks.max(axis=1)
    if n < y.size:  # the samples left over join the last run (a shorter run would narrow the band at the end)
        low[-1], high[-1] = min(low[-1], y[n:].min()), max(high[-1], y[n:].max())
        mid[-1] = t[n - per:].mean()
    return mid, low, high


#: At most this many samples of a time series are drawn as a line (the detail window): a window
#: with more is drawn as its band only, and the figure says to zoom in.
DETAIL_SAMPLES = 6000


def detail(t, y, t0: float, t1: float, limit: int = DETAIL_SAMPLES) -> tuple[np.ndarray, np.ndarray] | None:
    """Every sample of (t, y) in [t0, t1] (with one either side, so the line reaches the window's
    edges), or None where there are more than ``limit``."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    i0 = max(int(np.searchsorted(t, t0, side="left")) - 1, 0)
    i1 = min(int(np.searchsorted(t, t1, side="right")) + 1, t.size)
    if i1 - i0 > limit:
        return None
    return t[i0:i1], y[i0:i1]


def last_cycles(t_end: float, frequency_hz: float | None, cycles: int = 8, without: float = 2.0) -> tuple[float, float]:
    """The default view of a run: its last ``cycles`` cycles at ``frequency_hz`` (its last ``without``
    seconds where it has no dominant frequency), within the run."""
    span = cycles / frequency_hz if frequency_hz else without
    return max(0.0, t_end - span), t_end
