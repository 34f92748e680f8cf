"""What every branch and curve gives back: its special points, why it stopped, whether it closed.

:class:`SpecialPoint` is the one located-point type of every branch and curve (a one-parameter ``p``
on branches, ``(p1, p2)`` on Hopf curves; the curves of cycle bifurcations keep p1 in ``p`` and p2 in
their data). :class:`ContinuationResult` is the shape :class:`~.equilibria.EquilibriumBranch`,
:class:`~.periodic_orbits.PeriodicBranch`, :class:`~.hopf.HopfCurve` and
:class:`~.cycle_curves.CycleCurve` share; each adds its points' own columns.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .kinds import PointKind, Stop


@dataclass(frozen=True)
class SpecialPoint:
    """A bifurcation point (or a mark: an end, a turn) located on a branch or curve."""

    kind: PointKind
    p: float | tuple[float, float]
    index: int  # position in the branch's point list
    data: dict[str, Any] = field(default_factory=dict)
    #: Whether the search for the point reached its tolerance (False: the point is the nearest the
    #: search got, or an end of the step it lies in); None where no search was made (an end point).
    located: bool | None = None
    #: The located point's full solution where a follow-on analysis needs it (cycles:
    #: (mesh points, u)); not part of :meth:`to_dict`.
    solution: Any = field(default=None, repr=False, compare=False)

    def to_dict(self, parameter: str = "p") -> dict[str, Any]:
        """kind, the parameter, the data and ``located`` (where a search was made), in the key order
        of the JSON written when ``located`` was a data key: last, but before a torus curve's kappa."""
        data = dict(self.data)
        kappa = {"kappa": data.pop("kappa")} if "kappa" in data else {}
        located = {} if self.located is None else {"located": self.located}
        return {"kind": self.kind, parameter: self.p, **data, **located, **kappa}


@dataclass(kw_only=True)
class ContinuationResult:
    """The part every branch and curve shares."""

    special_points: list[SpecialPoint]
    stops: list[Stop]  # one per direction traced
    steps: int
    closed: bool = False  # a loop: the last point joins the first

    @property
    def stop_reasons(self) -> list[str]:
        return [s.message for s in self.stops]

    @property
    def stop_reason(self) -> str:
        """The stops' messages on one line."""
        return "; ".join(self.stop_reasons)

    def points_of(self, kind: PointKind) -> list[SpecialPoint]:
        """The special points of one kind, in order along the branch or curve."""
        return [s for s in self.special_points if s.kind == kind]

    def to_dict(self) -> dict[str, Any]:
        """The shared part as JSON-ready values; each result puts its own columns first."""
        return {"special_points": [s.to_dict() for s in self.special_points], "stop_reasons": self.stop_reasons,
                "steps": self.steps, "closed": self.closed}
