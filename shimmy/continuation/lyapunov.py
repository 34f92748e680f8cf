"""First Lyapunov coefficient of a Hopf point, for any smooth vector field.

Kuznetsov, Elements of Applied Bifurcation Theory (3rd ed.), eq. (3.20):

    l1 = Re[<p, C(q,q,qbar)> - 2 <p, B(q, A^-1 B(q,qbar))> + <p, B(qbar, (2 i w - A)^-1 B(q,q))>] / (2 w)

with A q = i w q, A^T p = -i w p, <q, q> = <p, q> = 1 (<a, b> = a^H b). In this
normalisation the planar normal form x' = -w y + s x (x^2 + y^2), y' = w x + s y (x^2 + y^2)
has l1 = 2 s / w.

B and C come from the analytic Jacobian: B(u, .) = Im J(i h u) / h (complex step, exact
to rounding) and C(u, w, .) = [B_{eps u}(w, .) - B_{-eps u}(w, .)] / (2 eps) (central
difference, relative error O(eps^2) in units of the state's nonlinearity scale).
"""

from __future__ import annotations

from typing import Callable

import numpy as np


def hopf_eigenvectors(A: np.ndarray, omega_hint: float | None = None):
    """q, p with A q = i w q, A^T p = -i w p, <q, q> = 1, <p, q> = 1 (<a, b> = a^H b): the pair
    with Im > 0 nearest the imaginary axis, or with ``omega_hint`` the eigenvalue nearest
    i omega_hint. Off a Hopf point (A's eigenvalue a + i w, a != 0) q and p are that eigenvalue's
    (A q = (a + i w) q), and w its imaginary part."""
    ev, vecs = np.linalg.eig(A)
    if omega_hint is None:
        i = np.argmin(np.abs(ev.real) + np.where(ev.imag > 0, 0.0, np.inf))
    else:
        i = np.argmin(np.abs(ev - 1j * abs(omega_hint)))
    omega = ev[i].imag
    q = vecs[:, i] / np.linalg.norm(vecs[:, i])
    evT, vecsT = np.linalg.eig(A.T)
    j = np.argmin(np.abs(evT - np.conj(ev[i])))
    p = vecsT[:, j]
    p = p / np.conj(np.vdot(p, q))
    return omega, q, p


def first_lyapunov_coefficient(jacobian: Callable[[np.ndarray], np.ndarray], n: int,
                               h: float = 1e-20, eps: float = 1e-4, omega_hint: float | None = None,
                               columns: Callable[[np.ndarray], np.ndarray] | None = None) -> float:
    """l1 at a Hopf point of the equilibrium x = 0 of x' = f(x) (Kuznetsov eq. 3.20).

    ``jacobian(x)`` must return df/dx and accept complex ``x`` (complex-analytic f).
    Negative l1: supercritical (stable small cycles); positive: subcritical. ``omega_hint``: the
    pair nearest i omega_hint (default: the pair nearest the imaginary axis). Evaluated off a Hopf
    point (the pair at a + i w) the same formula with that pair's vectors and w is a smooth function
    of the parameters equal to l1 on the Hopf curve: a test function whose zero on it is a
    generalised Hopf point.

    ``columns(X)``, optional: the Jacobians at the columns of a complex X (n, m) at once, (m, n, n) (a
    field vectorised over columns, as :class:`~shimmy.continuation.fields.TwoParameterField`'s): the
    eight complex evaluations then are one call, each column's arithmetic that of ``jacobian`` on it.
    """
    zero = np.zeros(n)
    A = jacobian(zero).real
    omega, q, p = hopf_eigenvectors(A, omega_hint)
    a, b = q.real, q.imag
    # B_w(base) = d/dt J(base + t w) at t = 0, by a complex step on the analytic Jacobian, at the eight
    # (w, base) the formula needs: B_a, B_b at 0, and at +-eps u the central differences in s of B_w(s u)
    # that make C(u, w) for (u, w) = (a, a), (b, b), (a, b)
    steps = ((a, zero), (b, zero), (a, eps * a), (a, -eps * a), (b, eps * b), (b, -eps * b), (b, eps * a),
             (b, -eps * a))
    points = [base + 1j * h * w for w, base in steps]
    if columns is not None:
        J = columns(np.stack(points, axis=1))
        Bs = [J[k].imag / h for k in range(len(points))]
    else:
        Bs = [jacobian(x).imag / h for x in points]
    Ba, Bb = Bs[0], Bs[1]
    C_aa, C_bb, C_ab = ((Bs[k] - Bs[k + 1]) / (2.0 * eps) for k in (2, 4, 6))

    def B(x_is_q: bool, y):  # B(q, y) or B(conj(q), y) for complex y
        return Ba @ y + (1j if x_is_q else -1j) * (Bb @ y)

    Bqq = Ba @ a - Bb @ b + 2j * (Ba @ b)
    Bqqbar = Ba @ a + Bb @ b
    Cqq = C_aa - C_bb + 2j * C_ab
    Cqqqbar = Cqq @ np.conj(q)
    term1 = np.vdot(p, Cqqqbar)
    term2 = -2.0 * np.vdot(p, B(True, np.linalg.solve(A, Bqqbar)))
    term3 = np.vdot(p, B(False, np.linalg.solve(2j * omega * np.eye(n) - A, Bqq)))
    return float((term1 + term2 + term3).real / (2.0 * omega))
