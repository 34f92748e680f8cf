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


def test_band_spans_every_cycle_and_detail_keeps_every_sample():
    import numpy as np
    from ui.series import band, detail, last_cycles

    t = np.arange(0, 60.0 + 1e-9, 0.002)
    y = np.sin(2 * np.pi * 16.0 * t)  # 16 Hz over 60 s: 30 001 samples
    mid, low, high = band(t, y, min_span=1.25 / 16.0)
    assert mid.size <= 2000 and np.all(np.diff(mid) > 0)
    assert low.max() < -0.99 and high.min() > 0.99  # every bucket holds a whole cycle: the band never narrows
    raw_mid, raw_low, raw_high = band(t, y)  # 2000 buckets of 15 samples, under a period at 16 Hz
    assert raw_high.min() < 0.99  # without min_span the band would be ragged
    x, v = detail(t, y, 10.0, 11.0)
    assert x[0] < 10.0 <= x[1] and x[-2] <= 11.0 < x[-1] and np.array_equal(v, y[(t >= x[0]) & (t <= x[-1])])
    assert detail(t, y, 0.0, 60.0) is None  # too many samples for a line
    assert last_cycles(60.0, 16.0) == (60.0 - 0.5, 60.0) and last_cycles(60.0, None) == (58.0, 60.0)
