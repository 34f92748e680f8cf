"""The map's regions, read off the classified slices along the continued region boundaries, so
that they follow the Hopf, fold and torus curves instead of stepping from slice to slice.

Between two consecutive boundary crossings of a row (a fixed load) the set of attractors, and so
the shimmy type, changes only where a stable cycle's mode changes (torsional / lateral / both:
a threshold on its amplitudes, not a bifurcation). Each interval of a row is named by the curves
that bound it (which curve, and which of its crossings of the row counted from low V); the same
interval exists on every slice between which and the row no boundary turns in Fz. The row's
interval takes the types of that interval on the slices that have it, as fractions of the
interval: the nearest slice below and above the row that have it, their breakpoints (mode
changes) interpolated linearly in Fz where both show the same sequence of types, else the
nearer one. An interval that no slice has (a region pinched between curves that no slice load
crosses) is what :func:`uncovered` reports, so that the map classifies a slice through it; one
left over is read off the nearest slice at the same speed, and counted.

The result is, per row, segments (V_low, V_high, type) whose ends lie on the curves (to the
polyline accuracy of the curves); from them the grid (:func:`grid`), the measure of each type
per row (:func:`measures`) and the region polygons (:func:`polygons`: trapezoids between
consecutive rows, chained into one polygon per region as long as it neither splits nor merges).
"""

from __future__ import annotations

from collections import defaultdict
from typing import Any, Sequence

import numpy as np

Curve = tuple[str, np.ndarray]  # (name, points (k, 2) in (V, Fz))
Segment = tuple[float, float, str]  # (V_low, V_high, type)
#: A piece of a slice's interval narrower than this fraction of it is taken as the rounding of
#: where the slice's located points and the curves' polylines put the same crossing.
SLIVER = 1e-3


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


def named_intervals(curves: Sequence[Curve], Fz: float, v_range: tuple[float, float]):
    """[(V_low, V_high, name)] between consecutive crossings of the load inside the speed range."""
    v_min, v_max = v_range
    inner = [(V, label) for V, label in crossings(curves, Fz) if v_min < V < v_max]
    edges = [(v_min, ("edge", 0))] + inner + [(v_max, ("edge", 1))]
    return [(edges[i][0], edges[i + 1][0], (edges[i][1], edges[i + 1][1])) for i in range(len(edges) - 1)]


def type_at(intervals: Sequence[dict[str, Any]], V: float) -> str:
    """A slice's type at V from its non-Stable intervals."""
    for iv in intervals:
        if iv["V_start"] <= V <= iv["V_end"]:
            return iv["type"]
    return "Stable"


def _pieces(intervals: Sequence[dict[str, Any]], a: float, b: float) -> list[tuple[float, float, str]]:
    """A slice's types on [a, b] as (fraction from, fraction to, type), slivers absorbed."""
    if b <= a:
        return [(0.0, 1.0, type_at(intervals, a))]
    cuts = sorted({0.0, 1.0} | {min(max((v - a) / (b - a), 0.0), 1.0) for iv in intervals
                               for v in (iv["V_start"], iv["V_end"])})
    raw = []
    for f0, f1 in zip(cuts[:-1], cuts[1:], strict=True):
        if f1 > f0:
            raw.append([f0, f1, type_at(intervals, a + 0.5 * (f0 + f1) * (b - a))])
    wide = [p for p in raw if p[1] - p[0] >= SLIVER] or [max(raw, key=lambda p: p[1] - p[0])]
    out: list[list] = []
    for p in wide:  # slivers go to the piece before them (or after, at the start)
        if out and out[-1][2] == p[2]:
            out[-1][1] = p[1]
        else:
            out.append(list(p))
    out[0][0], out[-1][1] = 0.0, 1.0
    for k in range(1, len(out)):
        out[k][0] = out[k - 1][1]
    return [tuple(p) for p in out]


def _interpolated(below, above, w: float):
    """Pieces of two slices with the same types, breakpoints interpolated (w = 0: below)."""
    return [(p[0] + w * (q[0] - p[0]), p[1] + w * (q[1] - p[1]), p[2]) for p, q in zip(below, above, strict=True)]


class _Slices:
    """The classified slices, each with its named intervals, for reading rows off."""

    def __init__(self, slices: Sequence[Any], curves: Sequence[Curve], v_range: tuple[float, float]):
        self.slices = sorted(slices, key=lambda s: s.Fz)
        self.loads = np.array([s.Fz for s in self.slices])
        self.named = [{name: (lo, hi) for lo, hi, name in named_intervals(curves, s.Fz, v_range)}
                      for s in self.slices]

    def having(self, name) -> list[int]:
        return [k for k, named in enumerate(self.named) if name in named]

    def pieces(self, k: int, name):
        a, b = self.named[k][name]
        return _pieces(self.slices[k].intervals, a, b)


def row_segments(slices: Sequence[Any], curves: Sequence[Curve], fz_rows: Sequence[float],
                 v_range: tuple[float, float]) -> tuple[list[list[Segment]], int]:
    """Each row's segments (V_low, V_high, type), merged, covering the speed range; and how many
    row intervals no slice has (read off the nearest slice at the same speed instead).
    ``slices`` carry ``Fz`` and ``intervals`` (see :class:`~shimmy.analyses.stability_map.SliceResult`)."""
    known = _Slices(slices, curves, v_range)
    rows, fallbacks = [], 0
    for Fz in fz_rows:
        segments: list[list] = []
        for lo, hi, name in named_intervals(curves, float(Fz), v_range):
            have = known.having(name)
            below = [k for k in have if known.loads[k] <= Fz]
            above = [k for k in have if known.loads[k] >= Fz]
            if have:
                k0 = below[-1] if below else None
                k1 = above[0] if above else None
                p0 = known.pieces(k0, name) if k0 is not None else None
                p1 = known.pieces(k1, name) if k1 is not None else None
                if p0 is not None and p1 is not None and k0 != k1 and [p[2] for p in p0] == [p[2] for p in p1]:
                    w = (Fz - known.loads[k0]) / (known.loads[k1] - known.loads[k0])
                    parts = _interpolated(p0, p1, float(w))
                elif p0 is not None and (p1 is None or Fz - known.loads[k0] <= known.loads[k1] - Fz):
                    parts = p0
                else:
                    parts = p1
                pieces = [(lo + f0 * (hi - lo), lo + f1 * (hi - lo), t) for f0, f1, t in parts]
            else:
                fallbacks += 1
                near = known.slices[int(np.argmin(np.abs(known.loads - Fz)))]
                parts = _pieces(near.intervals, lo, hi)
                pieces = [(lo + f0 * (hi - lo), lo + f1 * (hi - lo), t) for f0, f1, t in parts]
            for a, b, t in pieces:
                if segments and segments[-1][2] == t:
                    segments[-1][1] = b
                elif b > a or not segments:
                    segments.append([a, b, t])
        rows.append([tuple(s) for s in segments])
    return rows, fallbacks


def uncovered(loads: Sequence[float], curves: Sequence[Curve], fz_rows: Sequence[float],
              v_range: tuple[float, float], at_most: int = 8) -> list[float]:
    """Loads of further slices, so that every row interval (wider than a millionth of the range)
    exists on a slice at one of ``loads`` or at one of these: for each interval name no load has,
    the middle row load of those that have it, a load covering several names once; at most
    ``at_most``."""
    have = set()
    for Fz in loads:
        have |= {name for _, _, name in named_intervals(curves, float(Fz), v_range)}
    width = v_range[1] - v_range[0]
    missing: dict[Any, list[float]] = defaultdict(list)
    for Fz in fz_rows:
        for lo, hi, name in named_intervals(curves, float(Fz), v_range):
            if hi - lo > 1e-6 * width and name not in have:
                missing[name].append(float(Fz))
    extra: list[float] = []
    for name, at in sorted(missing.items(), key=lambda item: -len(item[1])):
        if name in have:
            continue
        Fz = at[len(at) // 2]
        extra.append(Fz)
        have |= {n for _, _, n in named_intervals(curves, Fz, v_range)}
        if len(extra) == at_most:
            break
    return sorted(extra)


def grid(rows: Sequence[Sequence[Segment]], v_grid: np.ndarray) -> list[list[str]]:
    """The type at each grid speed of each row."""
    out = []
    for segments in rows:
        highs = np.array([s[1] for s in segments])
        index = np.minimum(np.searchsorted(highs, v_grid, side="left"), len(segments) - 1)
        out.append([segments[int(k)][2] for k in index])
    return out


def measures(segments: Sequence[Segment]) -> dict[str, float]:
    """Measure (m/s) of each type on a row."""
    out: dict[str, float] = {}
    for lo, hi, t in segments:
        out[t] = out.get(t, 0.0) + (hi - lo)
    return out


def _split(segment: Segment, others: list[Segment]) -> list[tuple[float, float]]:
    """``segment`` cut among the overlapping segments of the next (or previous) row, at the
    middle of each gap between them."""
    cuts = [segment[0]]
    for k in range(len(others) - 1):
        cuts.append(min(max(0.5 * (others[k][1] + others[k + 1][0]), segment[0]), segment[1]))
    cuts.append(segment[1])
    return [(cuts[k], cuts[k + 1]) for k in range(len(others))]


def polygons(rows: Sequence[Sequence[Segment]], fz_rows: Sequence[float]) -> list[dict[str, Any]]:
    """The regions as polygons ``{"type", "V", "Fz"}`` (rings: the low-speed edge upwards, then
    the high-speed edge downwards). Between consecutive rows each segment is joined to the
    overlapping segments of its type in the other row (cut at the middle of the gaps where it meets
    several): trapezoids that tile the region; those of one region are chained into one polygon
    until it splits or merges. A segment with nothing of its type above (below) it tapers to
    its middle at the next (previous) row."""
    chains: list[dict[str, Any]] = []
    open_at: dict[int, dict[str, Any]] = {}  # segment index in the current row -> chain ending there whole
    for r in range(len(rows) - 1):
        A, B = rows[r], rows[r + 1]
        succ: dict[int, list[int]] = defaultdict(list)
        pred: dict[int, list[int]] = defaultdict(list)
        for i, a in enumerate(A):
            for j, b in enumerate(B):
                if a[2] == b[2] and a[0] < b[1] and b[0] < a[1]:
                    succ[i].append(j)
                    pred[j].append(i)
        part_a = {(i, j): part for i, js in succ.items()
                  for j, part in zip(js, _split(A[i], [B[j] for j in js]), strict=True)}
        part_b = {(i, j): part for j, is_ in pred.items()
                  for i, part in zip(is_, _split(B[j], [A[i] for i in is_]), strict=True)}
        following: dict[int, dict[str, Any]] = {}
        lower, upper = float(fz_rows[r]), float(fz_rows[r + 1])
        for i, a in enumerate(A):  # a region ending between the rows: a tip at the next row
            if i not in succ:
                mid = 0.5 * (a[0] + a[1])
                chain = open_at.pop(i, None)
                if chain is None:
                    chain = {"type": a[2], "rows": [(lower, a[0], a[1])]}
                    chains.append(chain)
                chain["rows"].append((upper, mid, mid))
        for j, b in enumerate(B):  # a region starting between the rows: a tip at the row below
            if j not in pred:
                mid = 0.5 * (b[0] + b[1])
                chain = {"type": b[2], "rows": [(lower, mid, mid), (upper, b[0], b[1])]}
                chains.append(chain)
                following[j] = chain
        for i, js in succ.items():
            for j in js:
                chain = open_at.pop(i, None) if len(js) == 1 else None
                if chain is None:
                    lo, hi = part_a[(i, j)]
                    chain = {"type": A[i][2], "rows": [(lower, lo, hi)]}
                    chains.append(chain)
                lo, hi = part_b[(i, j)]
                chain["rows"].append((upper, lo, hi))
                if len(pred[j]) == 1:
                    following[j] = chain
        open_at = following
    out = []
    for c in chains:
        up, down = c["rows"], c["rows"][::-1]
        out.append({"type": c["type"], "V": [p[1] for p in up] + [p[2] for p in down],
                    "Fz": [p[0] for p in up] + [p[0] for p in down]})
    return out


def polygon_area(polygon: dict[str, Any]) -> float:
    """Area (m/s x N) of a polygon, by the shoelace formula."""
    x, y = np.asarray(polygon["V"], float), np.asarray(polygon["Fz"], float)
    return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
