"""The mode changes of consecutive slices followed by their curves in (V, Fz), so that the map's rows between
two slices end a mode's piece where the change lies at the row's load, not where a straight line between
the slices puts it.

A slice's interval ends at a located mode change (:mod:`shimmy.analyses.diagrams.mode_changes`); between
two slices the shading used to interpolate such an end linearly in Fz: up to 1.2 m/s off the change's true
speed within one region, and 8-9.6 m/s where the regions' bounding curves differ between the slices and a
row read the nearer slice's fraction of its interval (measured: ``nes``, the lateral threshold between 306.7
and 405.6 kN). Two maps of one design whose slices lay at other loads (a warm map carries its neighbour's)
put it at other speeds.

A :class:`ModeLink` is the curve of one change from its slice's load to the next slice's, followed in the
load (:func:`~shimmy.analyses.diagrams.mode_changes.follow_load`; each point exact, chords within ~0.02-0.1
m/s of the curve). It is *joined* where it ends on the other slice's change of the same threshold (within
``MATCH``), else *open*: a piece of a mode one slice has and the next has not ends where the change's curve
meets the piece's other end (measured: ``nes_pd`` at rho_p 8580 kg/m^3, the lateral piece of 238.7 kN, whose
left end runs from 35.4 m/s up to ~45 m/s where it meets its right end just above 233.7 kN, had narrowed
linearly to where the next slice puts the mode's neighbours). Every change of a slice is followed up to the
next slice's load; a change of the upper slice whose threshold the lower slice has no change of is also
followed down. :func:`~shimmy.analyses.maps.map_shading.row_segments` reads a breakpoint off the link that
joins it on both slices, or that starts at it and reaches the row's load. A change whose curve the follow
loses (its relocation fails: it turns back in the load) has no curve (a *lost* record, with the last point
the follow reached), and is interpolated as before.

A warm map relocates a link's points other than the slices' changes at the new design, at their loads
(:class:`LinkPointsUnit`), between the two carried slices' relocated changes; links from or to slices
computed again or added are followed afresh. A change lost at the nearby design is resumed from the last
point that follow reached, relocated (a whole follow that loses a change costs 0.3-1 s; resumed, a few
relocations): lost again, it stays lost; if it now reaches the other slice's load it is followed afresh
from its slice, as a cold map follows it (nes_pd, a_p 0.9 -> 0.95: a change of 248.7 kN lost on the way
down to 233.7 kN at the nearby design reaches it at the new one).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ...model.configurations import Configuration
from ...model.parameters import Parameters
from ...model.units import kn
from ..diagrams.mode_changes import MIN_STEP_SHARE, ModeChange, follow_as_far, relocate

#: The end of a followed change and the other slice's change it is taken for lie within this (m/s): both
#: are located to 1e-7 m/s (measured 2e-9 to 8e-8 m/s apart on nes), changes of one threshold on one slice
#: lie metres per second apart.
MATCH = 1e-3
#: ``ModeLink.end`` of an open link, and of a change the follow lost (a record, so that a warm map resumes
#: the follow where it gave up instead of following it again: its points the change and the last one
#: reached, if any)
OPEN, LOST = -1, -2


@dataclass(frozen=True, eq=False)
class ModeLink:
    """The curve of a mode change from one slice's load to the next slice's: ``points`` in the order followed,
    the first the slice's change number ``start`` (in its ``mode_changes``), the last at the other slice's load:
    that slice's change number ``end`` (joined), or the followed point (open: ``end`` OPEN). ``end`` LOST:
    the follow lost the change (``points`` the change and the last point the follow reached, if any; ``to``
    the other slice's load)."""

    threshold: float
    start: int
    end: int
    points: tuple[ModeChange, ...]
    to: float | None = None  # the other slice's load where the follow lost the change

    @property
    def loads(self) -> tuple[float, float]:
        """(from, to): the loads of the slice followed from and of the one followed to."""
        return self.points[0].Fz, self.points[-1].Fz if self.to is None else self.to

    @property
    def joined(self) -> bool:
        return self.end >= 0

    def polyline(self) -> np.ndarray:
        """(k, 2) (V, Fz) by ascending Fz."""
        p = np.array([[c.V, c.Fz] for c in self.points], float)
        return p if p[0, 1] <= p[-1, 1] else p[::-1]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the points other than the slices' changes, with their cycles."""
        moved = self.points[1:-1] if self.joined else self.points[1:]  # a lost one: its last point reached
        return {"threshold": self.threshold, "start": self.start, "end": self.end, "loads": list(self.loads),
                "points": [c.to_dict(compact=True) for c in moved]}


def link_of(change: ModeChange, start: int, others: Sequence[ModeChange], followed: list[ModeChange] | None) -> \
        ModeLink | None:
    """The link of ``change`` (number ``start`` on its slice) from the points ``followed`` to the other slice's
    load (:func:`~shimmy.analyses.diagrams.mode_changes.follow_load`): joined to the other slice's change of the
    same threshold it reached (within MATCH), else open; lost if the follow did not reach the load (``followed``
    None)."""
    if followed is None:
        return None
    if not followed:
        raise ValueError("a follow to another load has points")
    end = followed[-1]
    near = [(abs(u.V - end.V), j) for j, u in enumerate(others) if u.threshold == change.threshold]
    if near and min(near)[0] <= MATCH:
        j = min(near)[1]
        return ModeLink(change.threshold, start, j, (change, *followed[:-1], others[j]))
    return ModeLink(change.threshold, start, OPEN, (change, *followed))


def follows(slices: Sequence[Any]) -> list[tuple[Any, Any, list[int]]]:
    """(from slice, to slice, numbers of the from slice's changes) to follow: between consecutive slices
    (by load), every change of the lower one up, and the changes of the upper one whose threshold the lower
    one has no change of down."""
    ordered = sorted(slices, key=lambda s: s.Fz)
    out = []
    for a, b in zip(ordered[:-1], ordered[1:]):
        if a.mode_changes:
            out.append((a, b, list(range(len(a.mode_changes)))))
        down = [j for j, c in enumerate(b.mode_changes) if all(u.threshold != c.threshold for u in a.mode_changes)]
        if down:
            out.append((b, a, down))
    return out


@dataclass(frozen=True, eq=False)
class ModeLinksUnit:
    """The links of the changes numbered ``only`` of one slice (``changes``) followed to the load of the next
    (whose changes are ``others``)."""

    config: Configuration
    params: Parameters
    changes: tuple[ModeChange, ...]
    others: tuple[ModeChange, ...]
    Fz_to: float
    exact_nes: bool
    only: tuple[int, ...]

    def run(self) -> list[ModeLink]:
        out = []
        for i in self.only:
            change = self.changes[i]
            followed, reached = follow_as_far(change, self.Fz_to, self.config, self.params, exact_nes=self.exact_nes)
            link = link_of(change, i, self.others, followed if reached else None)
            out.append(link if link is not None else
                       ModeLink(change.threshold, i, LOST, (change, *followed[-1:]), self.Fz_to))
        return out

    def describe(self) -> str:
        return f"mode changes followed from Fz = {kn(self.changes[0].Fz)} to {kn(self.Fz_to)}"


def links_unit(source: Any, target: Any, only: Sequence[int], config: Configuration, params: Parameters,
               exact_nes: bool) -> ModeLinksUnit:
    """The unit following the changes numbered ``only`` of slice ``source`` to slice ``target``'s load (two
    :class:`~shimmy.analyses.maps.map_slices.SliceResult`)."""
    return ModeLinksUnit(config, params, tuple(source.mode_changes), tuple(target.mode_changes), float(target.Fz),
                         exact_nes, tuple(only))


@dataclass(frozen=True, eq=False)
class LinkPointsUnit:
    """A nearby design's links' points other than the slices' changes relocated at this design, each at its
    load (:func:`~shimmy.analyses.diagrams.mode_changes.relocate`): per link, the points, or None if one was
    not found. A lost link's follow is resumed from its last point reached, relocated: the last point this
    follow reaches if it is lost again, or None if it reaches the other slice's load or that point is not
    found again (the link is then followed afresh, from its slice, as a cold map follows it)."""

    config: Configuration
    params: Parameters
    links: tuple[dict[str, Any], ...]  # ModeLink.to_dict() of the nearby design's map
    exact_nes: bool

    def run(self) -> list[list[ModeChange] | None]:
        out: list[list[ModeChange] | None] = []
        for link in self.links:
            if link["end"] == LOST:
                out.append(self._resumed(link))
                continue
            moved: list[ModeChange] | None = []
            for d in link["points"]:
                c = relocate(ModeChange.from_dict(d), self.config, self.params, exact_nes=self.exact_nes)
                if c is None:
                    moved = None
                    break
                moved.append(c)
            out.append(moved)
        return out

    def _resumed(self, link: dict[str, Any]) -> list[ModeChange] | None:
        if not link["points"]:
            return []
        last = relocate(ModeChange.from_dict(link["points"][-1]), self.config, self.params, exact_nes=self.exact_nes)
        if last is None:
            return None
        lo, hi = (float(f) for f in link["loads"])
        followed, reached = follow_as_far(last, hi, self.config, self.params, exact_nes=self.exact_nes,
                                          min_step=abs(hi - lo) * MIN_STEP_SHARE)
        return None if reached else [last, *followed][-1:]

    def describe(self) -> str:
        lo, hi = self.links[0]["loads"]
        return f"{len(self.links)} mode-change link(s) from Fz = {kn(lo)} to {kn(hi)} located again"


def carried_link(old: dict[str, Any], moved: list[ModeChange] | None, source: Any, target: Any) -> ModeLink | None:
    """A nearby design's link (``old``, :meth:`ModeLink.to_dict`) at this design: its points relocated
    (``moved``; None: one not found), from the carried slice ``source`` to the carried slice ``target`` (their
    relocated changes, numbered as before); None if it cannot be (a point or a change not found again)."""
    start, end, threshold = int(old["start"]), int(old["end"]), float(old["threshold"])
    if moved is None or start >= len(source.mode_changes) or end >= len(target.mode_changes):
        return None
    first = source.mode_changes[start]
    if first is None or first.threshold != threshold:
        return None
    if end == LOST:  # lost again where the follow was resumed (see LinkPointsUnit): not followed again
        return ModeLink(threshold, start, LOST, (first, *moved), float(target.Fz))
    if end == OPEN:  # open: joined now if its end reached a change of the other slice, as a cold map joins it
        return link_of(first, start, target.mode_changes, moved) if moved else None
    last = target.mode_changes[end]
    if last is None or last.threshold != threshold:
        return None
    return ModeLink(threshold, start, end, (first, *moved, last))


def polylines(links: Sequence[ModeLink]) -> list[np.ndarray]:
    """The links as (V, Fz) polylines, for :func:`~shimmy.analyses.maps.map_shading.row_segments` (a lost
    change's none)."""
    return [link.polyline() for link in links if link.end != LOST]
