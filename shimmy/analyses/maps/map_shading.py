"""The map's regions, read off the classified slices along the continued region boundaries, so
that they follow the Hopf, fold and torus curves instead of stepping from slice to slice.

Between two consecutive boundary crossings of a row (a fixed load) the set of attractors, and so
the shimmy type, changes only where a stable cycle's mode changes (torsional / lateral / both:
a threshold on its amplitudes, not a bifurcation). Each interval of a row is named by the curves
that bound it (which curve, and which of its crossings of the row counted from low V) and by
the run of loads over which that name persists (:func:`labelled`): the same region on every
slice between which and the row the name does not vanish. The row's
interval takes the types of that interval on the slices that have it, as fractions of the
interval: the nearest slice below and above the row that have it, their breakpoints (mode
changes) interpolated linearly in Fz where both show the same sequence of types or one has a
piece the other lacks (it narrows linearly to where it vanishes: no staircase), else the
nearer one. A breakpoint that a mode change's curve joins to the other slice's
(:mod:`~shimmy.analyses.maps.mode_links`) is read off that curve instead, also where the row reads one
slice alone. A region that no slice crosses (pinched between curves between two slice loads) is
what :func:`uncovered` reports, so that the map classifies a slice through it; one left over
(thinner than a grid cell or smaller than the map's threshold) is read off the nearest slice at
the same speed, and counted.

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
#: A curve's vertex within this fraction of a load lies on it (the location tolerance of its end points).
ON_LOAD = 1e-9


def crossings(curves: Sequence[Curve], Fz: float) -> list[tuple[float, tuple[str, int]]]:
    """(V, (curve name, crossing number from low V)) where each curve crosses the load Fz, by V."""
    found: list[tuple[float, str]] = []
    for name, p in curves:
        if len(p) < 2:
            continue
        # a vertex on the load to rounding (an end located on the box's edge: 899999.9999999998 N or
        # 900000.0000000008 N) is on it, so that whether a curve crosses an edge row is not rounding's
        p = p.copy()
        p[np.abs(p[:, 1] - Fz) <= ON_LOAD * max(abs(Fz), 1.0), 1] = Fz
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


def with_points(p: np.ndarray, points: Sequence[tuple[float, float]], reach: float = 0.01) -> np.ndarray:
    """The polyline ``p`` (k, 2) in (V, Fz) with located points of its curve (crossings of the slices'
    loads) put in as vertices, each into the segment that crosses its load nearest to it (within
    ``reach`` of its V, relative, at least 0.01 m/s; else left out), so that the curve crosses each such
    load where the point was located, not on a chord: 5 mm/s off a fold curve's crossing of 603.3 kN
    (nes), which a slice's interval ended at, left a piece of the next region 1e-3 of its interval wide
    inside it, and whether the shading kept such a sliver hung on the chord."""
    p = np.asarray(p, float).reshape(-1, 2)
    if len(p) < 2 or not len(points):
        return p
    inserts: list[tuple[int, float, float]] = []
    a, b = p[:-1], p[1:]
    for V, Fz in points:
        if np.any((np.abs(p[:, 0] - V) <= 1e-12 * max(abs(V), 1.0)) & (p[:, 1] == Fz)):
            continue  # a vertex already
        span = (a[:, 1] - Fz) * (b[:, 1] - Fz) <= 0.0
        span &= a[:, 1] != b[:, 1]
        ks = np.nonzero(span)[0]
        if ks.size == 0:
            continue
        f = (Fz - a[ks, 1]) / (b[ks, 1] - a[ks, 1])
        chord = a[ks, 0] + f * (b[ks, 0] - a[ks, 0])
        j = int(np.argmin(np.abs(chord - V)))
        if abs(chord[j] - V) <= max(reach * abs(V), 0.01):
            inserts.append((int(ks[j]), float(f[j]), (V, Fz)))
    if not inserts:
        return p
    rows = list(map(tuple, p))
    for k, _, point in sorted(inserts, key=lambda t: (t[0], t[1]), reverse=True):
        rows.insert(k + 1, point)
    return np.array(rows, float)


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


def _with_vanished(longer, shorter):
    """``shorter`` with the one piece of ``longer`` it lacks put back at zero width, so that the two have
    the same types and their breakpoints interpolate: a piece (a cycle's mode, such as Both) that one
    slice has and the next has not then narrows linearly in Fz to where it vanishes, instead of the rows
    switching from one slice's pieces to the other's halfway (a staircase edge). Where it sat: at the
    region's end for an end piece, at the breakpoint of ``shorter`` between its neighbours for an
    interior piece between two types, and at its centre on ``longer`` for one inside a single type
    (the neighbours merged). None if the two differ otherwise."""
    types_long, types_short = [p[2] for p in longer], [p[2] for p in shorter]
    if len(types_long) not in (len(types_short) + 1, len(types_short) + 2):
        return None
    for j in range(len(longer)):
        rest = types_long[:j] + types_long[j + 1:]
        merged = 0 < j < len(longer) - 1 and types_long[j - 1] == types_long[j + 1]
        if merged:
            rest = rest[:j] + rest[j + 1:]  # its neighbours are one piece on the other slice
        if rest != types_short:
            continue
        kind = types_long[j]
        if j == 0:
            return [(0.0, 0.0, kind)] + list(shorter)
        if j == len(longer) - 1:
            return list(shorter) + [(1.0, 1.0, kind)]
        if not merged:  # between shorter's pieces j - 1 and j
            at = shorter[j - 1][1]
            return list(shorter[:j]) + [(at, at, kind)] + list(shorter[j:])
        at = 0.5 * (longer[j][0] + longer[j][1])  # inside shorter's piece j - 1: split it there
        a0, a1, t = shorter[j - 1]
        at = min(max(at, a0), a1)
        return list(shorter[:j - 1]) + [(a0, at, t), (at, at, kind), (at, a1, t)] + list(shorter[j:])
    return None


def _aligned(p0, p1):
    """The pieces of two slices with one sequence of types (one piece that only one of them has put back
    on the other at zero width, :func:`_with_vanished`), or None."""
    if [p[2] for p in p0] == [p[2] for p in p1]:
        return p0, p1
    if len(p0) > len(p1):
        q1 = _with_vanished(p0, p1)
        return None if q1 is None else (p0, q1)
    q0 = _with_vanished(p1, p0)
    return None if q0 is None else (q0, p1)


def labelled(curves: Sequence[Curve], loads: Sequence[float], v_range: tuple[float, float]):
    """{load: [(V_low, V_high, region)]} for the loads in ascending order, where a region is an
    interval name with the number of its run: a name that vanishes between two loads (the curves
    bounding it pinch off or turn) and appears again names another region at the other load (the
    k-th crossings of two curves can bound the Torsion interval of low loads and a pocket of a
    high load alike)."""
    out: dict[float, list] = {}
    runs: dict[Any, int] = defaultdict(int)
    before: set = set()
    for Fz in sorted(set(float(f) for f in loads)):
        intervals = named_intervals(curves, Fz, v_range)
        names = {name for _, _, name in intervals}
        for name in names - before:
            runs[name] += 1
        before = names
        out[Fz] = [(lo, hi, (name, runs[name])) for lo, hi, name in intervals]
    return out


class _Slices:
    """The classified slices, each with its regions (:func:`labelled` over the rows and slice
    loads together), for reading rows off."""

    def __init__(self, slices: Sequence[Any], regions: dict[float, list]):
        self.slices = sorted(slices, key=lambda s: s.Fz)
        self.loads = np.array([s.Fz for s in self.slices])
        self.named = [{region: (lo, hi) for lo, hi, region in regions[float(s.Fz)]} for s in self.slices]

    def having(self, region) -> list[int]:
        return [k for k, named in enumerate(self.named) if region in named]

    def pieces(self, k: int, region):
        a, b = self.named[k][region]
        return _pieces(self.slices[k].intervals, a, b)


class _Links:
    """Mode changes' curves between two slices' loads (``links``: (k, 2) (V, Fz) polylines, taken by
    ascending Fz, :mod:`~shimmy.analyses.maps.mode_links`), found by their ends."""

    def __init__(self, links: Sequence[np.ndarray]):
        self.by_loads: dict[tuple[float, float], list[np.ndarray]] = defaultdict(list)
        self.by_end: dict[float, list[tuple[float, np.ndarray]]] = defaultdict(list)
        for p in links:
            p = np.asarray(p, float).reshape(-1, 2)
            if len(p) >= 2 and p[-1, 1] < p[0, 1]:
                p = p[::-1]
            if len(p) >= 2 and p[-1, 1] > p[0, 1]:
                self.by_loads[(float(p[0, 1]), float(p[-1, 1]))].append(p)
                self.by_end[float(p[0, 1])].append((float(p[0, 0]), p))
                self.by_end[float(p[-1, 1])].append((float(p[-1, 0]), p))

    def through(self, F: float, V: float, Fz: float, used: set) -> float | None:
        """V at load ``Fz`` on a link with an end at (V, F) whose other end lies at or beyond ``Fz``, if
        there is one (and not in ``used``: ids of links taken already; it is added)."""
        for end, p in self.by_end.get(float(F), ()):
            if id(p) not in used and abs(end - V) <= 1e-9 * max(abs(V), 1.0) and p[0, 1] <= Fz <= p[-1, 1]:
                used.add(id(p))
                return float(np.interp(Fz, p[:, 1], p[:, 0]))
        return None

    def speed(self, F0: float, V0: float, F1: float, V1: float, Fz: float, used: set) -> float | None:
        """V at load ``Fz`` on the link from (V0, F0) to (V1, F1), if there is one (ends within 1e-9 of
        the speeds, relative, at least 1e-9 m/s; not in ``used``, to which it is added)."""
        for p in self.by_loads.get((float(F0), float(F1)), ()):
            if id(p) not in used and abs(p[0, 0] - V0) <= 1e-9 * max(abs(V0), 1.0) \
                    and abs(p[-1, 0] - V1) <= 1e-9 * max(abs(V1), 1.0):
                used.add(id(p))
                return float(np.interp(Fz, p[:, 1], p[:, 0]))
        return None


def _placed(parts, speeds: list[float | None], row: tuple[float, float]):
    """``parts`` with breakpoint j at ``speeds[j]`` (m/s on the row's interval ``row``) where that is not
    None, every breakpoint then kept at or right of the one before (all placed first, then ordered: a
    piece whose end a link carries past its other end has zero width)."""
    lo, hi = row
    cuts = [p[1] for p in parts[:-1]]
    cuts = [min(max((V - lo) / (hi - lo), 0.0), 1.0) if V is not None else f for V, f in zip(speeds, cuts, strict=True)]
    cuts = list(np.maximum.accumulate(cuts)) if cuts else []
    edges = [0.0, *cuts, 1.0]
    return [(float(edges[k]), float(edges[k + 1]), parts[k][2]) for k in range(len(parts))]


def _along_links(parts, pair, ends: tuple[tuple[float, float], tuple[float, float]], loads: tuple[float, float],
                 row: tuple[float, float], Fz: float, links: _Links):
    """The interpolated ``parts`` of a row's interval ``row`` (between slices at ``loads`` whose aligned
    pieces are ``pair``, on their intervals ``ends``) with each breakpoint that a link joins on the two
    slices, or that a link from one of them reaches the row from, put where the link crosses the row
    (:func:`_placed`). A breakpoint beside a piece that one slice lacks (put back there at zero width,
    :func:`_with_vanished`) is not looked up on that slice: its two ends are one speed there, and a link
    from it belongs to one of them at most; each link is used once."""
    lo, hi = row
    if hi <= lo:
        return parts
    (a0, b0), (a1, b1) = ends
    used: set = set()
    speeds: list[float | None] = []
    for j in range(len(parts) - 1):
        V0 = a0 + pair[0][j][1] * (b0 - a0)
        V1 = a1 + pair[1][j][1] * (b1 - a1)
        whole = [pair[k][j][1] > pair[k][j][0] and pair[k][j + 1][1] > pair[k][j + 1][0] for k in (0, 1)]
        V = links.speed(loads[0], V0, loads[1], V1, Fz, used) if all(whole) else None
        if V is None and whole[0]:  # an open link from a slice's breakpoint that reaches the row
            V = links.through(loads[0], V0, Fz, used)
        if V is None and whole[1]:
            V = links.through(loads[1], V1, Fz, used)
        speeds.append(V)
    return _placed(parts, speeds, row)


def _through_links(parts, end: tuple[float, float], load: float, row: tuple[float, float], Fz: float,
                   links: _Links, used: set):
    """The ``parts`` of one slice (at ``load``, its interval ``end``) read for a row's interval ``row``
    (at ``Fz``), each breakpoint from which a link reaches the row's load put where the link crosses the
    row (:func:`_placed`): the slice's mode change followed to the row, where the next slice with its
    change lies in another region (the curves between them cross otherwise). The links taken are added to
    ``used``."""
    lo, hi = row
    if hi <= lo:
        return parts
    a, b = end
    return _placed(parts, [links.through(load, a + parts[j][1] * (b - a), Fz, used) for j in range(len(parts) - 1)],
                   row)


def _change_types(slice_: Any, V: float) -> tuple[str, str] | None:
    """(type left, type right) of a slice's change of type at speed V (an interval ending there and the next
    starting there, of other types), or None if the slice has no such change at V (within 1e-9)."""
    tol = 1e-9 * max(abs(V), 1.0)
    ivs = slice_.intervals
    for left, right in zip(ivs[:-1], ivs[1:]):
        if abs(left["V_end"] - V) <= tol and abs(right["V_start"] - V) <= tol and left["type"] != right["type"]:
            return left["type"], right["type"]
    return None


def _crossing_links(parts, load: float, row: tuple[float, float], Fz: float, links: _Links, known: "_Slices",
                    used: set):
    """The ``parts`` of a row's interval ``row`` read off the one slice (at ``load``) that crosses its region,
    with the changes of the next slice whose links come down (or up) into the interval put in: a link (not in
    ``used``) from a change of type on that slice (its two types there) whose end at ``load`` is no change of
    the slice read (open there), crossing the row's load at V inside the interval, splits the part it falls
    in at V into the change's left type up to V and its right type after, where that part is of one of those
    types (repeated until no link splits: one split can make the part another link falls in one of its types).
    The slice read may lack the mode the change bounds, where the curves between it and the change's slice
    differ: nes_pd (rho_p 8580 kg/m^3) between 233.7 and 248.7 kN, the lateral piece of 248.7 kN whose left
    end's change runs down to 46 m/s at 233.7 kN, where no lateral piece is left. The other type runs on to
    the part's end (the region's edge or the slice read's next change): where the piece ends between the
    slices is not known there."""
    lo, hi = row
    if hi <= lo:
        return parts
    k_read = np.flatnonzero(known.loads == load)
    if not len(k_read):
        return parts
    read = known.slices[int(k_read[0])]
    waiting = []
    for (F0, F1), ps in links.by_loads.items():
        if not (F0 < Fz < F1 and load in (F0, F1)):
            continue
        k_far = np.flatnonzero(known.loads == (F1 if load == F0 else F0))
        if not len(k_far):
            continue
        for p in ps:
            near, far = (p[0], p[-1]) if load == F0 else (p[-1], p[0])
            if id(p) in used or _change_types(read, float(near[0])) is not None:
                continue
            types = _change_types(known.slices[int(k_far[0])], float(far[0]))
            V = float(np.interp(Fz, p[:, 1], p[:, 0]))
            if types is not None and lo < V < hi:
                waiting.append(((V - lo) / (hi - lo), types, id(p)))
    while waiting:
        for item in waiting:
            f, types, ident = item
            j = next((j for j, (f0, f1, t) in enumerate(parts) if f0 < f < f1 and t in types), None)
            if j is not None:
                f0, f1, _ = parts[j]
                parts = [*parts[:j], (f0, f, types[0]), (f, f1, types[1]), *parts[j + 1:]]
                used.add(ident)
                waiting.remove(item)
                break
        else:
            break
    return parts


def row_segments(slices: Sequence[Any], curves: Sequence[Curve], fz_rows: Sequence[float],
                 v_range: tuple[float, float], links: Sequence[np.ndarray] = ()) -> tuple[list[list[Segment]], int]:
    """Each row's segments (V_low, V_high, type), merged, covering the speed range; and how many
    row intervals lie in a region no slice crosses (read off the nearest slice at the same speed
    instead). ``slices`` carry ``Fz`` and ``intervals`` (see
    :class:`~shimmy.analyses.maps.map_slices.SliceResult`). ``links``: the curves of mode changes between
    consecutive slices ((V, Fz) polylines by ascending Fz, :mod:`~shimmy.analyses.maps.mode_links`): a
    breakpoint of two slices that a link joins is read off the link at each row between them, not
    interpolated."""
    regions = labelled(curves, [float(f) for f in fz_rows] + [float(s.Fz) for s in slices], v_range)
    known = _Slices(slices, regions)
    joined = _Links(links)
    rows, fallbacks = [], 0
    for Fz in fz_rows:
        segments: list[list] = []
        for lo, hi, region in regions[float(Fz)]:
            have = known.having(region)
            below = [k for k in have if known.loads[k] <= Fz]
            above = [k for k in have if known.loads[k] >= Fz]
            if have:
                k0 = below[-1] if below else None
                k1 = above[0] if above else None
                p0 = known.pieces(k0, region) if k0 is not None else None
                p1 = known.pieces(k1, region) if k1 is not None else None
                pair = _aligned(p0, p1) if p0 is not None and p1 is not None and k0 != k1 else None
                if pair is not None:
                    w = (Fz - known.loads[k0]) / (known.loads[k1] - known.loads[k0])
                    parts = _interpolated(*pair, float(w))
                    if joined.by_loads:
                        parts = _along_links(parts, pair, (known.named[k0][region], known.named[k1][region]),
                                             (float(known.loads[k0]), float(known.loads[k1])), (lo, hi), float(Fz),
                                             joined)
                else:
                    k = k0 if p0 is not None and (p1 is None or Fz - known.loads[k0] <= known.loads[k1] - Fz) else k1
                    parts = p0 if k == k0 else p1
                    if joined.by_end:
                        used: set = set()
                        parts = _through_links(parts, known.named[k][region], float(known.loads[k]), (lo, hi),
                                               float(Fz), joined, used)
                        parts = _crossing_links(parts, float(known.loads[k]), (lo, hi), float(Fz), joined, known,
                                                used)
            else:
                fallbacks += 1
                near = known.slices[int(np.argmin(np.abs(known.loads - Fz)))]
                parts = _pieces(near.intervals, lo, hi)
            for f0, f1, t in parts:
                a, b = lo + f0 * (hi - lo), lo + f1 * (hi - lo)
                if segments and segments[-1][2] == t:
                    segments[-1][1] = b
                elif b > a or not segments:
                    segments.append([a, b, t])
        rows.append([tuple(s) for s in segments])
    return rows, fallbacks


def uncovered(loads: Sequence[float], curves: Sequence[Curve], fz_rows: Sequence[float],
              v_range: tuple[float, float], min_width: float = 0.0, min_area: float = 0.0,
              at_most: int = 8) -> list[float]:
    """Loads of further slices, so that every region between the curves that is at least
    ``min_width`` (m/s) wide on some row and covers ``min_area`` (m/s x N, over the rows) is
    crossed by a slice at one of ``loads`` or at one of these: for each such region no load
    crosses, largest first, the row load where it is widest; a load crossing several once; at
    most ``at_most``. (A thinner sliver is read off the nearest slice at the same speed.)"""
    regions = labelled(curves, [float(f) for f in fz_rows] + [float(f) for f in loads], v_range)
    have = set()
    for Fz in loads:
        have |= {region for _, _, region in regions[float(Fz)]}
    step = float(fz_rows[1] - fz_rows[0]) if len(fz_rows) > 1 else 0.0
    area: dict[Any, float] = defaultdict(float)
    widest: dict[Any, tuple[float, float]] = {}
    for Fz in fz_rows:
        for lo, hi, region in regions[float(Fz)]:
            if region in have or hi <= lo:
                continue
            area[region] += (hi - lo) * step
            if hi - lo > widest.get(region, (0.0, 0.0))[0]:
                widest[region] = (hi - lo, float(Fz))
    extra: list[float] = []
    for region in sorted(area, key=lambda r: -area[r]):
        if region in have or widest[region][0] < min_width or area[region] < min_area:
            continue
        Fz = widest[region][1]
        extra.append(Fz)
        have |= {r for _, _, r in regions[Fz]}
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
    several), and those with nothing of their type in the other row fill the gaps between those
    joins as triangles: pieces that tile the strip between the rows. Those of one region are
    chained into one polygon until it splits or merges."""
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
        # Between consecutive links (and the row ends) lies a gap: [bottom_lo, bottom_hi] on this row,
        # [top_lo, top_hi] on the next, holding segments of this row with nothing of their type above
        # (regions ending between the rows) and of the next with nothing below (regions starting).
        # The diagonal from (top_lo, next row) to (bottom_hi, this row) cuts the gap in two triangles:
        # the ending segments fan out from its top corner, the starting ones from its bottom corner,
        # so that the pieces tile the gap.
        links = sorted(part_a, key=lambda key: part_a[key][0])
        edges_a = [A[0][0]] + [x for key in links for x in part_a[key]] + [A[-1][1]]
        edges_b = [B[0][0]] + [x for key in links for x in part_b[key]] + [B[-1][1]]
        ending = [i for i in range(len(A)) if i not in succ]
        starting = [j for j in range(len(B)) if j not in pred]
        for g in range(len(links) + 1):
            bottom_lo, bottom_hi = edges_a[2 * g], edges_a[2 * g + 1]
            top_lo, top_hi = edges_b[2 * g], edges_b[2 * g + 1]
            for i in ending:
                a = A[i]
                if bottom_lo <= 0.5 * (a[0] + a[1]) <= bottom_hi:
                    chain = open_at.pop(i, None)
                    if chain is None:
                        chain = {"type": a[2], "rows": [(lower, a[0], a[1])]}
                        chains.append(chain)
                    chain["rows"].append((upper, top_lo, top_lo))
            for j in starting:
                b = B[j]
                if top_lo <= 0.5 * (b[0] + b[1]) <= top_hi:
                    chain = {"type": b[2], "rows": [(lower, bottom_hi, bottom_hi), (upper, b[0], b[1])]}
                    chains.append(chain)
                    following[j] = chain
            ending = [i for i in ending if not bottom_lo <= 0.5 * (A[i][0] + A[i][1]) <= bottom_hi]
            starting = [j for j in starting if not top_lo <= 0.5 * (B[j][0] + B[j][1]) <= top_hi]
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


def cells_off_edges(reference: Sequence[Sequence[str]], other: Sequence[Sequence[str]]) -> list[tuple[int, int]]:
    """The cells (row, column) where ``other``'s grid differs from ``reference``'s away from every edge
    of ``reference``'s regions: its eight neighbours (those inside the grid) all of the cell's type. A
    warm map's grid against the cold map's of the same design should have none (a cell differing beside
    an edge is the curves' or the slices' rounding)."""
    a, b = np.asarray(reference), np.asarray(other)
    if a.shape != b.shape:
        raise ValueError(f"grids of shapes {a.shape} and {b.shape}")
    padded = np.pad(a, 1, mode="edge")  # a border cell's outside neighbours: copies of cells it has
    rows, cols = a.shape
    uniform = np.ones(a.shape, bool)
    for di in (0, 1, 2):
        for dj in (0, 1, 2):
            uniform &= padded[di:di + rows, dj:dj + cols] == a
    return [(int(i), int(j)) for i, j in np.argwhere(uniform & (a != b))]
