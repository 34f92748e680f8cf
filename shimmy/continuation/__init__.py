"""A continuation engine for any x' = f(x, p): equilibria, periodic orbits, Hopf curves.

Generic: numpy and scipy only (numba compiles the condensed LU), nothing of the landing gear; tested on
textbook systems.

* :mod:`.kinds`: :class:`PointKind`, the kinds of special point (H, LP, LPC, NS, PD, GH, ...), and
  :class:`Stop` / :class:`StopReason`, why a branch or curve ended.
* :mod:`.fields`: the systems continued, :class:`VectorField` x' = f(x, p) and
  :class:`TwoParameterField` x' = f(x, p1, p2).
* :mod:`.results`: the one :class:`SpecialPoint` type and :class:`ContinuationResult`, the shape
  every branch and curve shares (special points, stops, closed, steps, ``to_dict``).
* :mod:`.core`: pseudo-arclength continuation of F(u) = 0 (predictor, bordered Newton
  corrector, step control, location of special points).
* :mod:`.equilibria`: equilibrium branches with eigenvalues, Hopf (H), fold (LP) and branch
  (BP) points.
* :mod:`.collocation` and :mod:`.periodic_orbits`: periodic orbits by orthogonal collocation
  (boundary-value problem in the period), Floquet multipliers, fold (LPC), torus (NS),
  period-doubling (PD) and branch (BPC) points of cycles.
* :mod:`.cycle_curves`: two-parameter curves of folds (LPC), period doublings (PD) and tori (NS)
  of cycles, with their codimension-2 points: a package, the shared bordered machinery
  (``bordered``), one module per defining system (``fold_of_cycles``, ``period_doubling``,
  ``torus``), the tracing driver (``tracing``) and the codimension-2 detection (``codim2``);
* :mod:`.hopf`: two-parameter Hopf curves with generalised Hopf (GH), double-Hopf (HH) and
  zero-Hopf (ZH) points; :mod:`.lyapunov`: the first Lyapunov coefficient.

Continue any ``f(x, p)``: the supercritical Hopf normal form x' = p x - y - x r^2,
y' = x + p y - y r^2 has x = 0 stable for p < 0, a Hopf point at p = 0 and the stable
cycle r = sqrt(p) with period 2 pi for p > 0::

    import numpy as np
    from shimmy.continuation import (Mesh, PeriodicOptions, PointKind, VectorField, equilibrium_branch,
                                     hopf_eigenvectors, hopf_guess, periodic_branch)

    def f(x, p):
        r2 = x[0] ** 2 + x[1] ** 2
        return np.stack([p * x[0] - x[1] - x[0] * r2, x[0] + p * x[1] - x[1] * r2])

    def dfdx(x, p):  # (n, n) for x (n,), (m, n, n) for x (n, m)
        x0, x1 = x[0], x[1]
        J = np.empty(np.shape(x)[1:] + (2, 2))
        J[..., 0, 0] = p - 3 * x0 ** 2 - x1 ** 2
        J[..., 0, 1] = -1 - 2 * x0 * x1
        J[..., 1, 0] = 1 - 2 * x0 * x1
        J[..., 1, 1] = p - x0 ** 2 - 3 * x1 ** 2
        return J

    hopf_normal_form = VectorField(2, f, dfdx, lambda x, p: x.copy(), "hopf")
    eq = equilibrium_branch(hopf_normal_form, np.zeros(2), -0.5, p_range=(-0.5, 0.5))
    H = next(s for s in eq.special_points if s.kind == PointKind.HOPF)  # H.p ~ 0, H.data["omega"] ~ 1
    omega, q, _ = hopf_eigenvectors(dfdx(np.array(H.data["x"]), H.p))
    options = PeriodicOptions(ntst=20, ncol=4)
    guess, shape = hopf_guess(np.array(H.data["x"]), H.p, omega, q,
                              Mesh.uniform(options.ntst, options.ncol), 0.0)
    cycles = periodic_branch(hopf_normal_form, guess, p_range=(-0.5, 0.5), options=options, direction=shape)
    # cycles.p, cycles.period (~2 pi), cycles.x_max[:, 0] (~ sqrt(p)), cycles.stable (True)

Errors: :class:`InvalidInputError` for bad options or starts, :class:`ConvergenceError` when
a start does not converge; both derive from :class:`ContinuationError`. A branch or curve says
why it ended in its ``stops``: a :class:`StopReason` and a message for each direction traced.
"""

from .lazy import lazy_exports

#: Where each public name lives: imported on first use (the collocation kernels load numba).
_EXPORTS = {
    "Mesh": ".collocation", "PeriodicProblem": ".collocation",
    "ContinuationOptions": ".core", "CurvePoint": ".core", "CurveProblem": ".core", "Tracer": ".core",
    "correct": ".core", "locate": ".core", "point_at": ".core", "step": ".core", "tangent": ".core",
    "weighted_norm": ".core",
    "CODIM2_KINDS": ".cycle_curves", "CycleCurve": ".cycle_curves", "CycleCurveOptions": ".cycle_curves",
    "CycleCurveProblem": ".cycle_curves", "cycle_curve": ".cycle_curves", "start_beside": ".cycle_curves",
    "join_halves": ".cycle_curves",
    "EquilibriumBranch": ".equilibria", "equilibrium_branch": ".equilibria",
    "ContinuationError": ".errors", "ConvergenceError": ".errors", "InvalidInputError": ".errors",
    "TwoParameterField": ".fields", "VectorField": ".fields",
    "HopfCurve": ".hopf", "HopfCurveProblem": ".hopf", "hopf_curve": ".hopf", "hopf_start": ".hopf",
    "CYCLE_BIFURCATIONS": ".kinds", "PointKind": ".kinds", "Stop": ".kinds", "StopReason": ".kinds",
    "first_lyapunov_coefficient": ".lyapunov", "hopf_eigenvectors": ".lyapunov",
    "OrbitGuess": ".periodic_orbits", "PeriodicBranch": ".periodic_orbits", "PeriodicOptions": ".periodic_orbits",
    "hopf_guess": ".periodic_orbits", "orbit_from_samples": ".periodic_orbits", "periodic_branch": ".periodic_orbits",
    "ContinuationResult": ".results", "SpecialPoint": ".results",
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

__all__ = [
    "CODIM2_KINDS", "CYCLE_BIFURCATIONS", "ContinuationError", "ContinuationOptions", "ContinuationResult",
    "ConvergenceError", "CurvePoint", "CurveProblem", "CycleCurve", "CycleCurveOptions", "CycleCurveProblem",
    "EquilibriumBranch", "HopfCurve", "HopfCurveProblem", "InvalidInputError", "Mesh", "OrbitGuess",
    "PeriodicBranch", "PeriodicOptions", "PeriodicProblem", "PointKind", "SpecialPoint", "Stop", "StopReason",
    "Tracer", "TwoParameterField", "VectorField", "correct", "cycle_curve", "equilibrium_branch", "join_halves",
    "first_lyapunov_coefficient", "hopf_curve", "hopf_eigenvectors", "hopf_guess", "hopf_start", "locate",
    "orbit_from_samples", "periodic_branch", "point_at", "start_beside", "step", "tangent", "weighted_norm",
]
