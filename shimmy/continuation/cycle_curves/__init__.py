"""Two-parameter curves of cycle bifurcations: folds (LPC), period doublings (PD) and
Neimark-Sacker / torus (NS) points of periodic orbits.

Formulation: minimally augmented systems with bordered test functions on the collocation
discretisation of :mod:`shimmy.continuation.collocation` (Doedel, Govaerts, Kuznetsov,
*Computation of periodic solution bifurcations in ODEs using bordered systems*, SIAM J. Numer.
Anal. 41, 2003; the
formulation MATCONT's ``limitpointcycle``, ``perioddoubling`` and ``neimarksacker`` curves
use). Chosen over the fully extended systems because the unknowns are the cycle's plus one
parameter (plus kappa for NS) instead of doubling (PD, LPC) or tripling (NS) them; the cost per
Newton step is one sparse LU more than a cycle's, and the test functions are regular at the
bifurcation, so Newton converges quadratically up to the finite-difference second
derivatives.

Laid out as MATCONT (one curve type per defining system) and BifurcationKit.jl (``codim2/``) do:

* :mod:`.bordered`: the shared machinery, :class:`CycleCurveProblem`: the cycle's equations and
  the bordered test matrix [[A, B], [C^T, 0]], its factors, solves and gradients;
* :mod:`.defining_system`: what differs per curve type, and one module per type holding its A,
  test functions, borders and codimension-2 points: :mod:`.fold_of_cycles` (LPC: A the Jacobian
  of the cycle equations in (x, T)), :mod:`.period_doubling` (PD: the linearised collocation with
  v(0) + v(1) = 0), :mod:`.torus` (NS: two periods with v(0) - 2 kappa v(1) + v(2) = 0);
* :mod:`.tracing`: :func:`cycle_curve` and :func:`start_beside`, the curve traced both ways with
  its ends, turns and marks in p2 (or one way: :func:`join_halves` joins two halves traced apart);
* :mod:`.codim2`: detection and location of the codimension-2 points along a curve.
"""

from .bordered import DEFINING_SYSTEMS, CycleCurveProblem
from .tracing import CycleCurve, CycleCurveOptions, cycle_curve, join_halves, start_beside

#: Codimension-2 points reported on each curve type.
CODIM2_KINDS = {kind: system.codim2 for kind, system in DEFINING_SYSTEMS.items()}

__all__ = ["CODIM2_KINDS", "CycleCurve", "CycleCurveOptions", "CycleCurveProblem", "cycle_curve", "join_halves",
           "start_beside"]
