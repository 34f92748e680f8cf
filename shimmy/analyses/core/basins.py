"""Basins of attraction by simulation: how large a disturbance ends on which attractor.

Nothing here knows the gear. A *probe* maps a batch of disturbances to labels: each disturbance a
row of an array, in coordinates in which its size is the Euclidean norm (the gear's: the energy
norm, :mod:`shimmy.analyses.maps.margins`); each label the attractor the run from it ends on (an
integer >= 0), :data:`UNSETTLED` if it settled on none of them in the time allowed, :data:`FAILED`
if the integration failed. The caller runs a batch as it likes (the gear's runs go side by side
through an executor); the functions here do the bookkeeping of sizes and labels, and are tested
on textbook systems whose basins are known in closed form.

* **Thresholds along a direction** (:func:`scan`, then :func:`refine`): the runs from a geometric
  grid of sizes (the bracketing scan, one batch), then every bracket (the largest size probed
  below the first size that ends on an attractor, and that first size) is divided in its
  geometric ratio, ``split`` interior sizes per bracket and round (as many as the workers allow),
  until the bracket is within ``rtol`` of its upper end. A size probed inside a bracket that ends
  on a third attractor opens that attractor's bracket there: each attractor's threshold is the
  smallest size found to reach it. A basin thinner than the scan's grid step along the
  direction can be missed (the scan decides which brackets exist).
* **The smallest threshold over all directions** (:func:`smallest_over_directions`): the
  thresholds along a fixed sweep of directions (the axes and the diagonals of every pair of
  axes: m^2 directions in m dimensions for a field symmetric under x -> -x, else 2 m^2), then a
  pattern search on the unit sphere from the best: the 2(m - 1) directions at angle ``a`` around
  it are each probed once, just below its threshold; one that reaches the attractor there has a
  smaller threshold (bracketed downwards, then refined) and becomes the best, else ``a`` is
  halved, down to ``min_angle``. Local: a minimum further than the sweep's spacing (45 degrees)
  from the best swept direction can be missed.
* **Basin fractions** (:func:`sample_ball`, :func:`wilson`): disturbances sampled uniformly in
  the ball of a given radius (seeded: the same seed, the same points) and the share ending on
  each attractor with its 95 % Wilson score interval.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

#: The label of a run that settled on no attractor in the time allowed.
UNSETTLED = -1
#: The label of a run whose integration failed.
FAILED = -2

#: Interior sizes per bracket and round at most (three divide a bracket by four).
MAX_SPLIT = 3
#: Rounds of refinement at most (each divides every open bracket at least by two).
MAX_ROUNDS = 60
#: The 95 % quantile of the standard normal distribution (two-sided intervals).
Z95 = 1.959963984540054

Probe = Callable[[np.ndarray], Sequence[int]]


@dataclass(frozen=True)
class Threshold:
    """The smallest size along a direction that ends on ``label``: in (``lower``, ``upper``].

    ``upper`` is the smallest size probed that reaches the attractor, ``lower`` the largest probed
    below it (which does not; ``lower_label`` is where it ends), or 0 when the smallest size probed
    already reaches it (the threshold is then below the smallest size: ``value`` 0, ``tolerance``
    that size)."""

    label: int
    lower: float
    upper: float
    lower_label: int | None

    @property
    def value(self) -> float:
        return 0.0 if self.lower == 0.0 else 0.5 * (self.lower + self.upper)

    @property
    def tolerance(self) -> float:
        return self.upper if self.lower == 0.0 else 0.5 * (self.upper - self.lower)


@dataclass
class Ray:
    """The runs along one direction (a unit vector): sizes probed and the label of each."""

    direction: np.ndarray
    sizes: list[float] = field(default_factory=list)
    labels: list[int] = field(default_factory=list)

    def add(self, size: float, label: int) -> None:
        k = int(np.searchsorted(self.sizes, size))
        self.sizes.insert(k, float(size))
        self.labels.insert(k, int(label))

    def reached(self) -> list[int]:
        """The attractors some probed size reaches, in the order of their first size."""
        return list(dict.fromkeys(label for label in self.labels if label >= 0))

    def threshold(self, label: int) -> Threshold | None:
        """The bracket of the smallest probed size that ends on ``label`` (None if none does)."""
        for k, here in enumerate(self.labels):
            if here == label:
                if k == 0:
                    return Threshold(label, 0.0, self.sizes[0], None)
                return Threshold(label, self.sizes[k - 1], self.sizes[k], self.labels[k - 1])
        return None

    def open_brackets(self, rtol: float) -> list[tuple[float, float]]:
        """The brackets (lower, upper) of the attractors reached, wider than ``rtol`` of their upper end."""
        out = []
        for label in self.reached():
            t = self.threshold(label)
            if t is not None and t.lower > 0.0 and t.upper - t.lower > rtol * t.upper:
                out.append((t.lower, t.upper))
        return list(dict.fromkeys(out))


def geometric_sizes(low: float, high: float, count: int) -> np.ndarray:
    """``count`` sizes from ``low`` to ``high`` in a constant ratio (the bracketing scan's grid)."""
    return np.geomspace(low, high, count)


def probe_points(rays_and_sizes: list[tuple[Ray, float]], probe: Probe) -> None:
    """Run every (ray, size) in one batch and record the labels on the rays."""
    if not rays_and_sizes:
        return
    points = np.array([s * ray.direction for ray, s in rays_and_sizes])
    labels = probe(points)
    for (ray, s), label in zip(rays_and_sizes, labels, strict=True):
        ray.add(s, int(label))


def scan(rays: list[Ray], sizes: Sequence[float], probe: Probe) -> None:
    """The bracketing scan: every size along every ray, in one batch."""
    probe_points([(ray, float(s)) for ray in rays for s in sizes], probe)


def refine(rays: list[Ray], probe: Probe, rtol: float, width: int = 1) -> int:
    """Divide every open bracket of every ray until each is within ``rtol`` (relative to its upper end);
    each round probes ``split`` geometric interior sizes per bracket, ``split`` = workers / brackets
    (1 to :data:`MAX_SPLIT`), in one batch. Returns the number of rounds."""
    for rounds in range(MAX_ROUNDS):
        active = [(ray, lo, hi) for ray in rays for lo, hi in ray.open_brackets(rtol)]
        if not active:
            return rounds
        split = max(1, min(MAX_SPLIT, width // len(active)))
        probe_points([(ray, lo * (hi / lo) ** (j / (split + 1))) for ray, lo, hi in active
                      for j in range(1, split + 1)], probe)
    return MAX_ROUNDS


def sweep_directions(m: int, symmetric: bool = True) -> np.ndarray:
    """The unit axes and the diagonals (e_i +- e_j)/sqrt(2) of every pair: m^2 directions, one of each pair
    u, -u (``symmetric``: a field with f(-x) = -f(x) ends -x on the mirror image of where x ends); else
    their negatives too."""
    eye = np.eye(m)
    rows = [eye[i] for i in range(m)]
    for i in range(m):
        for j in range(i + 1, m):
            rows += [(eye[i] + eye[j]) / math.sqrt(2.0), (eye[i] - eye[j]) / math.sqrt(2.0)]
    out = np.array(rows)
    return out if symmetric else np.vstack([out, -out])


def tangent_basis(u: np.ndarray) -> np.ndarray:
    """An orthonormal basis (rows) of the plane orthogonal to the unit vector ``u``."""
    q, _ = np.linalg.qr(np.column_stack([u, np.eye(u.size)]))
    return q[:, 1:u.size].T


@dataclass(frozen=True)
class Smallest:
    """The smallest threshold found over all directions for one attractor: its direction (a unit
    vector), its bracket, the directions tried, and how the pattern search ended (``angle``: the last
    angle tried, rad)."""

    label: int
    direction: np.ndarray
    threshold: Threshold
    directions_tried: int
    angle: float


def smallest_over_directions(probe: Probe, m: int, sizes: Sequence[float], rtol: float, *, width: int = 1,
                             symmetric: bool = True, min_angle: float = math.radians(1.0),
                             max_moves: int = 20) -> tuple[list[Ray], dict[int, Smallest]]:
    """The sweep's rays (scanned and refined) and, for every attractor reached along some direction, the
    smallest threshold over all directions (see the module docstring)."""
    rays = [Ray(u) for u in sweep_directions(m, symmetric)]
    scan(rays, sizes, probe)
    refine(rays, probe, rtol, width)
    labels = list(dict.fromkeys(label for ray in rays for label in ray.reached()))
    best: dict[int, Smallest] = {}
    for label in labels:
        found = [(ray.threshold(label), ray) for ray in rays if label in ray.labels]
        t, ray = min(found, key=lambda pair: (pair[0].upper, pair[0].value))
        best[label] = _pattern_search(probe, label, ray, t, rtol, width, min_angle, max_moves, len(rays))
    return rays, best


def _pattern_search(probe: Probe, label: int, ray: Ray, t: Threshold, rtol: float, width: int,
                    min_angle: float, max_moves: int, tried: int) -> Smallest:
    """Move from ``ray`` to a neighbouring direction while one reaches ``label`` below its threshold."""
    angle = math.pi / 8.0  # half the sweep's spacing
    m = ray.direction.size
    if t.lower == 0.0 or m < 2:
        return Smallest(label, ray.direction, t, tried, 0.0)
    moves = 0
    while angle >= min_angle and moves < max_moves:
        u = ray.direction
        basis = tangent_basis(u)
        candidates = [Ray(math.cos(angle) * u + math.sin(angle) * sign * b) for b in basis for sign in (1.0, -1.0)]
        test = t.lower
        probe_points([(c, test) for c in candidates], probe)
        tried += len(candidates)
        hits = [c for c in candidates if c.labels[0] == label]
        if not hits:
            angle /= 2.0
            continue
        for c in hits:  # bracket downwards: sizes 5 % apart below the test size, a batch at a time
            step = 0
            while c.labels[0] == label and step < 40:
                probe_points([(c, test * 0.95 ** (step + j)) for j in range(1, max(2, width) + 1)], probe)
                step += max(2, width)
        refine(hits, probe, rtol, width)
        better = [(c.threshold(label), c) for c in hits]
        better = [(bt, c) for bt, c in better if bt is not None and bt.upper < t.upper]
        if not better:
            angle /= 2.0
            continue
        t, ray = min(better, key=lambda pair: pair[0].upper)
        moves += 1
    return Smallest(label, ray.direction, t, tried, angle)


def sample_ball(m: int, radius: float, samples: int, seed: int) -> np.ndarray:
    """``samples`` points uniform in the m-ball of ``radius`` (a direction uniform on the sphere, the
    radius as radius * U^(1/m)), reproducible from ``seed``."""
    rng = np.random.default_rng(seed)
    g = rng.standard_normal((samples, m))
    g /= np.linalg.norm(g, axis=1)[:, None]
    return g * (radius * rng.random(samples) ** (1.0 / m))[:, None]


def wilson(count: int, total: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a proportion ``count`` / ``total`` (95 % by default)."""
    if total <= 0:
        return 0.0, 1.0
    p = count / total
    denominator = 1.0 + z * z / total
    centre = (p + z * z / (2 * total)) / denominator
    half = z / denominator * math.sqrt(p * (1 - p) / total + z * z / (4 * total * total))
    return max(0.0, centre - half), min(1.0, centre + half)
