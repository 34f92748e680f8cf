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
