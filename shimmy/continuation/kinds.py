"""The engine's vocabulary: the kinds of special point and why a branch or curve stopped.

A :class:`PointKind` is a ``str`` (``enum.StrEnum``): ``PointKind.HOPF == "H"``, it formats as
``"H"`` and serialises to JSON as ``"H"``, so results written before these types existed read the
same. The labels are AUTO-07p's and MATCONT's (BifurcationKit.jl's ``:hopf``, ``:bp``, ``:lpc``,
``:ns``, ``:pd``, ``:gh``, ...): H, LP, BP on equilibria; LPC, NS, PD, BPC on cycles; GH, HH (double
Hopf), ZH (zero-Hopf) on Hopf curves; CPC, LPNS, LPPD, PDNS and the strong resonances R1-R4 on
curves of cycles. "PD" is period doubling here, never the particle damper.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass


class PointKind(enum.StrEnum):
    """Kinds of located point, with AUTO-07p's / MATCONT's labels as values."""

    # equilibria, one parameter
    HOPF = "H"
    FOLD = "LP"
    BRANCH_POINT = "BP"
    # cycles, one parameter
    FOLD_OF_CYCLES = "LPC"
    TORUS = "NS"
    PERIOD_DOUBLING = "PD"
    BRANCH_POINT_OF_CYCLES = "BPC"
    # Hopf curves, two parameters
    GENERALISED_HOPF = "GH"
    DOUBLE_HOPF = "HH"
    ZERO_HOPF = "ZH"
    # curves of cycles, two parameters
    CUSP_OF_CYCLES = "CPC"
    FOLD_TORUS = "LPNS"
    FOLD_FLIP = "LPPD"
    FLIP_TORUS = "PDNS"
    RESONANCE_1_1 = "R1"
    RESONANCE_1_2 = "R2"
    RESONANCE_1_3 = "R3"
    RESONANCE_1_4 = "R4"
    # marks on a branch or curve, not bifurcations
    END = "EP"  # located on a bound of the range or box
    ZERO_AMPLITUDE = "ZA"  # a curve of cycles shrinking onto an equilibrium
    P2_TURN = "P2_TURN"  # a two-parameter curve turning in its second parameter
    P2_MARK = "P2_MARK"  # a two-parameter curve crossing a requested value of its second parameter

    @property
    def is_mark(self) -> bool:
        """True for the marks (ends, zero amplitude, turns and crossings in p2), not bifurcations."""
        return self in _MARKS


_MARKS = frozenset({PointKind.END, PointKind.ZERO_AMPLITUDE, PointKind.P2_TURN, PointKind.P2_MARK})

#: The bifurcations of cycles a one-parameter branch reports, and the curves that continue them.
CYCLE_BIFURCATIONS = (PointKind.FOLD_OF_CYCLES, PointKind.TORUS, PointKind.PERIOD_DOUBLING)


class StopReason(enum.StrEnum):
    """Why a branch, or one direction of a curve, ended; its :class:`Stop`'s message says where."""

    BOUND = "bound"  # reached a bound of the parameter range or box (the end located on it)
    CLOSED = "closed"  # returned to its first point: a closed branch or curve, traversed once
    STEP_BUDGET = "step_budget"  # ``max_steps`` used
    NEWTON_FAILED = "newton_failed"  # the step fell below ``ds_min`` without a converged point
    PERIOD_LIMIT = "period_limit"  # a cycle's period above ``period_max``
    NONPOSITIVE_PERIOD = "nonpositive_period"  # the continuation left the curve
    ZERO_AMPLITUDE = "zero_amplitude"  # cycles shrank onto an equilibrium (a Hopf or codimension-2 point)
    ZERO_FREQUENCY = "zero_frequency"  # a Hopf curve's omega fell to zero (Bogdanov-Takens)
    PAST_RESONANCE = "past_resonance"  # a torus curve's kappa left [-1, 1]: neutral saddle cycles, not tori
    LIMITS = "limits"  # the caller's ``limits`` check (e.g. a model's range of validity)
    REQUESTED_POINT = "requested_point"  # the first point of a kind in ``PeriodicOptions.stop_at``


@dataclass(frozen=True)
class Stop:
    """Why a branch, or one direction of a curve, ended: ``reason`` to test, ``message`` to read
    (and to write: results give the message, never the reason)."""

    reason: StopReason
    message: str
