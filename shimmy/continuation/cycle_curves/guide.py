"""A trace that follows the points of the same curve at a nearby design (a warm start's guide).

One slider step moves a curve of cycle bifurcations a little: its points at the new design lie next
to those at the old one, and the old trace's points are where the step control put them (each
step's chord and turn within their limits). A :class:`Guide` holds the old curve's points in the
order a half trace meets them, and predicts each new point from them: the old point k plus the
*shift* the last new point has from its own old point,

    u_pred(k) = u_old(k) + (u_new(k - 1) - u_old(k - 1)),

corrected by Newton on the hyperplane through it normal to the old curve's chord there. Its error
is how much the shift changes over one step, O(design change x step), where a tangent predictor's
is O(step^2) x curvature: Newton converges in fewer chord iterations, and no step is refused for
its length. Each point is taken only where the tracer takes a step (converged, ahead, turned and
chord within the tracer's limits: :meth:`~shimmy.continuation.core.Tracer.advance_to`), so a point
of a guided trace is a point of the curve to the same tolerance as any other, and the trace's
checks (the box, the zero-amplitude end, closure, turns, marks, codimension-2 points) are the
same. A step may pass over old points the drawn polyline does not need (:meth:`Guide.next`); refused,
it is taken again to the next old point. Where a guided point is refused, the tracer takes that step
itself and the guide resumes at its first point ahead; once its points are used up, or it stopped helping (``GIVE_UP``,
``SLOW``), the tracer goes on alone (a curve that grew is traced on to its new end).

Old points are stored in float32 (:func:`encode`): a predictor needs no more, and the warm start
stays ~1.2 MB for a map's curves (`nes`).
"""

from __future__ import annotations

import base64
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..collocation import Mesh
from ..core import CurvePoint, weighted_norm


def encode(a: np.ndarray) -> str:
    """An array as base64 float32 (JSON-ready)."""
    return base64.b64encode(np.asarray(a, np.float32).tobytes()).decode("ascii")


def decode(text: str) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), np.float32).astype(float)


def on_mesh(u: np.ndarray, source: Mesh, target: Mesh, n: int) -> np.ndarray:
    """A curve point (or difference of points) u = (x at ``source``'s nodes, then the scalars T, p1,
    p2[, kappa]) with x evaluated at ``target``'s nodes (the collocation polynomials; linear in u)."""
    if source.points.size == target.points.size and np.array_equal(source.points, target.points):
        return u
    n_x = source.n_nodes * n
    return np.concatenate([source.evaluate(u[:n_x].reshape(source.n_nodes, n), target.node_times).ravel(), u[n_x:]])


def guide_points(curve, i: int, plus_to_last: bool) -> dict[int, list[tuple[np.ndarray, np.ndarray]]]:
    """The points of a traced curve (a :class:`~.tracing.CycleCurve`) from its point ``i`` on, each
    way: {+1: towards the curve's last point if ``plus_to_last`` else its first, -1: the other way};
    a closed curve's all round, back to point i. Each (mesh points, u = (x, T, p1, p2[, kappa]))."""
    count = len(curve.p)
    has_kappa = bool(np.isfinite(curve.kappa[i]))

    def point(k: int) -> tuple[np.ndarray, np.ndarray]:
        mesh, u = curve.solutions[k]
        tail = [curve.p[k, 1]] + ([curve.kappa[k]] if has_kappa else [])
        return np.asarray(mesh, float), np.concatenate([u, tail])

    up, down = list(range(i, count)), list(range(i, -1, -1))
    if curve.closed:
        up, down = up + list(range(1, i + 1)), down + list(range(count - 2, i - 1, -1))
    first, second = (up, down) if plus_to_last else (down, up)
    return {1: [point(k) for k in first], -1: [point(k) for k in second]}


#: A guide is given up after this many of its points in a row were refused, or once a point it predicted took
#: more than SLOW Newton iterations (a tangent predictor's step takes 4-5): where the curve's end
#: moved with the design (a GH point moving along the curve), late guided points took 11-22
#: iterations and the refused ones up to 8 factorisations each, twice the unguided trace's work.
GIVE_UP = 2
SLOW = 6
#: A guided step goes at most this many old points ahead, passing over at most REACH - 1 of them (those the
#: drawn polyline does not need: see :meth:`Guide.next`)
REACH = 4


@dataclass
class Guide:
    """The points of the same curve at a nearby design, in the order a half trace meets them: the
    first is the one the trace starts from (its seed), each (mesh points, u = (x, T, p1, p2[, kappa]))."""

    points: list[tuple[np.ndarray, np.ndarray]]
    ncol: int
    n: int
    at: int = 0  # the old point the trace's last point corresponds to
    k: int = 1  # the next old point to predict from
    #: the new point's shift from its old point (u_new - u_old) and the mesh it is on
    shift: tuple[Mesh, np.ndarray] | None = None
    refused: int = 0
    taken: int = 0
    misses: int = 0  # points refused since the last one taken
    _moved: dict = field(default_factory=dict)  # k -> (mesh, old point k on it): each moved once a mesh

    def _old(self, k: int, mesh: Mesh) -> np.ndarray:
        """Old point k on ``mesh`` (next(), took() and the step after ask for the same point)."""
        kept = self._moved.get(k)
        if kept is None or kept[0] is not mesh:
            points, u = self.points[k]
            kept = self._moved[k] = (mesh, on_mesh(np.asarray(u, float), Mesh(np.asarray(points, float), self.ncol),
                                                   mesh, self.n))
        return kept[1]

    def anchor(self, point: CurvePoint, mesh: Mesh) -> None:
        """The trace's first point, the guide's first point corrected at the new design (a trace
        starts the guide over)."""
        self.at, self.k, self.taken, self.refused, self.misses = 0, 1, 0, 0, 0
        self.shift = (mesh, point.u - self._old(0, mesh))

    def stop(self) -> None:
        """The guide does not help here (the curve moved too far from the old one): the trace goes on
        alone."""
        self.k = len(self.points)

    def _shift(self, mesh: Mesh) -> np.ndarray:
        source, d = self.shift
        return on_mesh(d, source, mesh, self.n)

    def next(self, mesh: Mesh,
             passes: Callable[[int, int], bool] | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """(predictor, the old curve's chord into it) for the next point on ``mesh``; None once the
        guide is used up. ``passes(a, b)``: whether a step may go from old point a straight to old point
        b > a + 1, passing over the points between (the trace's own test); the next point is then the
        last b of a + 2, a + 3, ... (at most a + ``REACH``) before the first that does not pass, except right
        after a refused point (the trace resumes point by point)."""
        if self.shift is None or self.k >= len(self.points):
            return None
        if passes is not None and self.misses == 0:
            while self.k + 1 < len(self.points) and self.k + 1 - self.at <= REACH and passes(self.at, self.k + 1):
                self.k += 1
        old = self._old(self.k, mesh)
        return old + self._shift(mesh), old - self._old(self.at, mesh)

    def shorter(self) -> bool:
        """After a refused step that passed over old points: the next old point instead (True), or
        False where the step went to the next one already."""
        if self.k <= self.at + 1:
            return False
        self.k = self.at + 1
        return True

    def olds(self, a: int, b: int, mesh: Mesh) -> np.ndarray:
        """Old points a..b on ``mesh``, one row each."""
        return np.array([self._old(k, mesh) for k in range(a, b + 1)])

    def took(self, point: CurvePoint, mesh: Mesh) -> None:
        """The predicted point was taken (``point``): the shift is its, the guide moves on (or stops,
        if the point was slow to converge)."""
        self.shift = (mesh, point.u - self._old(self.k, mesh))
        self.at = self.k
        self.k += 1
        self.taken += 1
        self.misses = 0
        if point.iterations > SLOW:
            self.stop()

    def skip_behind(self, point: CurvePoint, mesh: Mesh, weights: np.ndarray) -> None:
        """After a step the tracer took itself (the guided one refused): on to the first old point
        (shifted) ahead of ``point`` along its tangent."""
        self.refused += 1
        self.misses += 1
        if self.misses >= GIVE_UP:
            self.stop()
            return
        self.k = self.at + 1
        while self.k < len(self.points):
            ahead = self._old(self.k, mesh) + self._shift(mesh) - point.u
            if float(np.sum(weights * ahead * point.tangent)) > 0.0 and weighted_norm(ahead, weights) > 0.0:
                break
            self.k += 1
        self.at = self.k - 1
