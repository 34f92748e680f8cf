"""The drawn envelope of a long time series (ui/series.py)."""

import math

import numpy as np

from ui.series import ENVELOPE_BUCKETS, envelope


def test_envelope_keeps_every_bucket_extreme_in_time_order_and_short_series_whole():
    t = np.arange(30001) * 0.002  # a 60 s run at 2 ms
    y = 0.1 * np.sin(2 * np.pi * 16.02 * t) * (1 - np.exp(-t / 5)) + 1e-4 * np.random.default_rng(0).normal(size=t.size)
    y[12345] = 0.5  # a lone spike must survive
    x, v = envelope(t, y)
    assert v.size <= 2 * ENVELOPE_BUCKETS and np.all(np.diff(x) > 0)
    assert v.max() == 0.5 and v.min() == y.min()
    per = math.ceil(y.size / ENVELOPE_BUCKETS)
    for start in range(0, y.size, per):  # every bucket's lowest and highest sample is drawn
        chunk = slice(start, min(start + per, y.size))
        for i in (start + int(np.argmin(y[chunk])), start + int(np.argmax(y[chunk]))):
            assert t[i] in x
    short = np.linspace(0.0, 1.0, 2 * ENVELOPE_BUCKETS)
    x, v = envelope(short, short ** 2)
    np.testing.assert_array_equal(v, short ** 2)
