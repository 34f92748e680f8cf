"""The map's shading on a fine (V, Fz) grid, read off the classified slices along the continued
region boundaries, so that it follows the Hopf, fold and torus curves instead of stepping from
slice to slice.

Between two consecutive boundary crossings of a row (a fixed load) the set of attractors, and so
the shimmy type, does not change. Each interval of a row is named by the curves that bound it
(which curve, and which of its crossings of the row counted from low V); the same interval
exists on the nearest classified slice as long as no boundary turns between them, and the
row's interval is that slice interval mapped linearly onto it (a speed at a fraction f of the
row's interval takes the slice's type at the same fraction of the slice's interval). Where the slice has
no interval of that name (a boundary turns in Fz between the row and the slice, or a region
pinches off), the type is read off the nearest slice at the same speed, as before. The shading
then agrees with the curves to the polyline accuracy of the curves in every row.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

Curve = tuple[str, np.ndarray]  # (name, points (k, 2) in (V, Fz))


def crossings(curves: Sequence[Curve], Fz: float) -> list[tuple[float, tuple[str, int]]]:
    """(V, (curve name, crossing number from low V)) where each curve crosses the load Fz, by V."""
    found: list[tuple[float, str]] = []
    for name, p in curves:
        if len(p) < 2:
            continue
        a, b = p[:-1], p[1:]
        # half-open segments: a vertex exactly on the load (a curve's start point) counts once
        hit = ((a[:, 1] < Fz) & (Fz <= b[:, 1])) | ((b[:, 1] < Fz) & (Fz <= a[:, 1]))
        for k in np.nonzero(hit)[0]:
            f = (Fz - a[k, 1]) / (b[k, 1] - a[k, 1])
            found.append((float(a[k, 0] + f * (b[k, 0] - a[k, 0])), name))
    found.sort()
    count: dict[str, int] = {}
    out = []
    for V, name in found:
        count[name] = count.get(name, 0) + 1
        out.append((V, (name, count[name])))
    return out


def _intervals(cross: list[tuple[float, tuple[str, int]]], v_min: float, v_max: float):
    """[(V_low, V_high, name)] between consecutive crossings inside [v_min, v_max]."""
    inner = [(V, label) for V, label in cross if v_min < V < v_max]
    edges = [(v_min, ("edge", 0))] + inner + [(v_max, ("edge", 1))]
    return [(edges[i][0], edges[i + 1][0], (edges[i][1], edges[i + 1][1])) for i in range(len(edges) - 1)]


def type_at(intervals: Sequence[dict[str, Any]], V: float) -> str:
    """A slice's type at V from its non-Stable intervals."""
    for iv in intervals:
        if iv["V_start"] <= V <= iv["V_end"]:
            return iv["type"]
    return "Stable"


def measures(intervals: Sequence[dict[str, Any]], lo: float, hi: float) -> dict[str, float]:
    """Measure (m/s) of each type of a slice inside [lo, hi] (Stable: what no interval covers)."""
    out: dict[str, float] = {}
    for iv in intervals:
        overlap = min(hi, iv["V_end"]) - max(lo, iv["V_start"])
        if overlap > 0:
            out[iv["type"]] = out.get(iv["type"], 0.0) + overlap
    out["Stable"] = out.get("Stable", 0.0) + max(0.0, (hi - lo) - sum(out.values()))
    return out


def shade(slices: Sequence[Any], curves: Sequence[Curve], v_grid: np.ndarray, fz_rows: np.ndarray,
          v_range: tuple[float, float]) -> tuple[list[list[str]], list[dict[str, float]], int]:
    """Types on the grid v_grid x fz_rows, the exact measure (m/s) of each type on every row (the
    mapped slice intervals, not the cells), and how many row intervals fell back to the nearest
    slice at the same speed. ``slices`` carry ``Fz`` and ``intervals`` (see
    :class:`~shimmy.analyses.stability_map.SliceResult`)."""
    loads = np.array([s.Fz for s in slices])
    named = []
    for s in slices:
        ivs = _intervals(crossings(curves, s.Fz), *v_range)
        named.append({name: (lo, hi) for lo, hi, name in ivs})
    rows: list[list[str]] = []
    lengths: list[dict[str, float]] = []
    fallbacks = 0
    for Fz in fz_rows:
        order = np.argsort(np.abs(loads - Fz), kind="stable")
        row = ["Stable"] * len(v_grid)
        length: dict[str, float] = {}
        for lo, hi, name in _intervals(crossings(curves, float(Fz)), *v_range):
            k = next((int(j) for j in order[:2] if name in named[int(j)]), None)
            cells = np.nonzero((v_grid >= lo) & (v_grid <= hi))[0]
            if k is not None:  # the same interval on the slice, mapped linearly onto this row's
                a, b = named[k][name]
                for c in cells:
                    f = 0.5 if hi == lo else (v_grid[c] - lo) / (hi - lo)
                    row[c] = type_at(slices[k].intervals, float(a + f * (b - a)))
                scale = (hi - lo) / (b - a) if b > a else 0.0
                part = {t: m * scale for t, m in measures(slices[k].intervals, a, b).items()}
            else:
                fallbacks += 1
                near = slices[int(order[0])]
                for c in cells:
                    row[c] = type_at(near.intervals, float(v_grid[c]))
                part = measures(near.intervals, lo, hi)
            for t, m in part.items():
                length[t] = length.get(t, 0.0) + m
        rows.append(row)
        lengths.append(length)
    return rows, lengths, fallbacks
