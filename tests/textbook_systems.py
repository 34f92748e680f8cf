"""Textbook vector fields with known bifurcations, in the form the continuation engine takes.

Every system is a :class:`shimmy.continuation.VectorField` with hand-derived Jacobians,
vectorised over columns: ``f(x, p)`` takes x of shape (n,) or (n, m); ``dfdx`` returns
(n, n) or (m, n, n). The known answers are stated next to each system.
"""

from __future__ import annotations

import math

import numpy as np

from shimmy.continuation import VectorField


def _jacobian(entries, x: np.ndarray) -> np.ndarray:
    """(n, n) for x (n,), (m, n, n) for x (n, m) from a nested list of scalars / (m,) arrays."""
    n = len(entries)
    J = np.empty(np.shape(x)[1:] + (n, n))
    for i, row in enumerate(entries):
        for j, value in enumerate(row):
            J[..., i, j] = value
    return J


# --------------------------------------------------------------------------- equilibria


def fold_1d() -> VectorField:
    """x' = p - x^2: fold LP at (x, p) = (0, 0); x = +sqrt(p) stable, -sqrt(p) unstable."""
    return VectorField(
        1,
        lambda x, p: p - x ** 2,
        lambda x, p: _jacobian([[-2.0 * x[0]]], x),
        lambda x, p: np.ones_like(x),
        "fold_1d",
    )


def fold_2d(c: float = 0.3) -> VectorField:
    """x' = p - x^2 - c y, y' = x - y: equilibria y = x, p = x^2 + c x.

    Fold where dp/dx = 0: x = -c/2, p = -c^2/4. Jacobian [[-2x, -c], [1, -1]],
    determinant 2x + c: the branch x > -c/2 is stable (trace < 0 there for c < 2),
    x < -c/2 has one positive eigenvalue.
    """
    return VectorField(
        2,
        lambda x, p: np.stack([p - x[0] ** 2 - c * x[1], x[0] - x[1]]),
        lambda x, p: _jacobian([[-2.0 * x[0], -c], [1.0, -1.0]], x),
        lambda x, p: np.stack([np.ones_like(x[0]), np.zeros_like(x[0])]),
        "fold_2d",
    )


def pitchfork() -> VectorField:
    """x' = p x - x^3, y' = -y: the trivial branch has a branch point BP at p = 0."""
    return VectorField(
        2,
        lambda x, p: np.stack([p * x[0] - x[0] ** 3, -x[1]]),
        lambda x, p: _jacobian([[p - 3.0 * x[0] ** 2, 0.0], [0.0, -1.0]], x),
        lambda x, p: np.stack([x[0], np.zeros_like(x[1])]),
        "pitchfork",
    )


def transcritical() -> VectorField:
    """x' = p x - x^2: the branches x = 0 and x = p cross at p = 0 (BP); they exchange stability."""
    return VectorField(
        1,
        lambda x, p: p * x - x ** 2,
        lambda x, p: _jacobian([[p - 2.0 * x[0]]], x),
        lambda x, p: x.copy(),
        "transcritical",
    )


# --------------------------------------------------------------------------- planar normal forms


def planar_normal_form(g=lambda p: p, dg=lambda p: 1.0, a1: float = -1.0, a2: float = 0.0, w0: float = 1.0,
                       c: float = 0.0, name: str = "hopf") -> VectorField:
    """x' = G x - W y, y' = W x + G y with G = g(p) + a1 r^2 + a2 r^4, W = w0 + c r^2.

    In polar form r' = r G(p, r^2), theta' = W(r^2). The equilibrium 0 has eigenvalues
    g(p) +- i w0: Hopf points where g = 0. Cycles: r0^2 > 0 with G(p, r0^2) = 0, period
    2 pi / W(r0^2), nontrivial Floquet exponent d(r G)/dr = 2 r0^2 (a1 + 2 a2 r0^2), so the
    nontrivial multiplier is exp(2 r0^2 (a1 + 2 a2 r0^2) T).
    """

    def parts(x, p):
        r2 = x[0] ** 2 + x[1] ** 2
        G = g(p) + a1 * r2 + a2 * r2 ** 2
        W = w0 + c * r2
        return r2, G, W

    def f(x, p):
        _, G, W = parts(x, p)
        return np.stack([G * x[0] - W * x[1], W * x[0] + G * x[1]])

    def dfdx(x, p):
        r2, G, W = parts(x, p)
        dG = a1 + 2.0 * a2 * r2  # dG/d(r^2)
        X, Y = x[0], x[1]
        Gx, Gy, Wx, Wy = 2 * X * dG, 2 * Y * dG, 2 * c * X, 2 * c * Y
        return _jacobian([[G + X * Gx - Y * Wx, -W + X * Gy - Y * Wy],
                          [W + X * Wx + Y * Gx, G + X * Wy + Y * Gy]], x)

    def dfdp(x, p):
        return dg(p) * np.asarray(x, float)

    return VectorField(2, f, dfdx, dfdp, name)


def hopf_supercritical(omega: float = 2.0) -> VectorField:
    """x' = mu x - w y - x r^2, ...: cycles r^2 = mu, T = 2 pi / w, multiplier exp(-2 mu T)."""
    return planar_normal_form(w0=omega, name="hopf_supercritical")


def hopf_subcritical_quintic(omega: float = 1.0) -> VectorField:
    """r' = mu r + r^3 - r^5: fold of cycles at mu = -1/4, r^2 = 1/2.

    Cycles r^2 = (1 +- sqrt(1 + 4 mu)) / 2; the inner (minus) one is born at mu = 0 and is
    unstable, the outer one is stable. Exponent 2 r^2 (1 - 2 r^2).
    """
    return planar_normal_form(a1=1.0, a2=-1.0, w0=omega, name="hopf_subcritical_quintic")


def hopf_twice(omega: float = 1.0) -> VectorField:
    """Growth rate g = mu (1 - mu): Hopf points at 0 and 1, cycles r^2 = mu (1 - mu) between them."""
    return planar_normal_form(g=lambda p: p * (1.0 - p), dg=lambda p: 1.0 - 2.0 * p, w0=omega, name="hopf_twice")


def hopf_close_pair(delta: float, centre: float = 0.5, omega: float = 1.0) -> VectorField:
    """Growth rate g = (p - centre)^2 - delta^2: Hopf points at centre -+ delta, unstable outside them.

    With delta much smaller than a continuation step, both crossings fall inside one step and
    the number of unstable eigenvalues is the same at its two ends.
    """
    return planar_normal_form(g=lambda p: (p - centre) ** 2 - delta ** 2, dg=lambda p: 2.0 * (p - centre),
                              w0=omega, name="hopf_close_pair")


def two_pairs(delta: float, centre: float = 0.5) -> VectorField:
    """Two uncoupled planar normal forms with growth rates p - centre and p - centre - delta
    (frequencies 1 and 2): two Hopf points delta apart, both pairs turning unstable."""
    first = planar_normal_form(g=lambda p: p - centre, w0=1.0)
    second = planar_normal_form(g=lambda p: p - centre - delta, w0=2.0)

    def f(x, p):
        x = np.asarray(x, float)
        return np.concatenate([first.f(x[:2], p), second.f(x[2:], p)])

    def dfdx(x, p):
        x = np.asarray(x, float)
        J = np.zeros(x.shape[1:] + (4, 4))
        J[..., :2, :2], J[..., 2:, 2:] = first.dfdx(x[:2], p), second.dfdx(x[2:], p)
        return J

    def dfdp(x, p):
        return np.asarray(x, float).copy()

    return VectorField(4, f, dfdx, dfdp, "two_pairs")


def hopf_shear(omega: float = 2.0, c: float = -1.0) -> VectorField:
    """Rotation W = w + c r^2: cycles r^2 = mu with period 2 pi / (w + c mu) (grows for c < 0)."""
    return planar_normal_form(w0=omega, c=c, name="hopf_shear")


def van_der_pol() -> VectorField:
    """x'' - mu (1 - x^2) x' + x = 0 as x' = y, y' = mu (1 - x^2) y - x; Hopf at mu = 0 (omega 1)."""
    return VectorField(
        2,
        lambda x, p: np.stack([x[1], p * (1.0 - x[0] ** 2) * x[1] - x[0]]),
        lambda x, p: _jacobian([[0.0, 1.0], [-2.0 * p * x[0] * x[1] - 1.0, p * (1.0 - x[0] ** 2)]], x),
        lambda x, p: np.stack([np.zeros_like(x[1]), (1.0 - x[0] ** 2) * x[1]]),
        "van_der_pol",
    )


# Van der Pol limit cycle at mu = 1 (published, e.g. the period tables of Van der Pol's equation;
# reproduced in the tests by an independent tight-tolerance integration).
VDP_PERIOD_MU1 = 6.6632868593231
VDP_AMPLITUDE_MU1 = 2.0086198608748


# --------------------------------------------------------------------------- constructed 4-D systems


def neimark_sacker(w1: float = 1.0, w2: float = math.sqrt(2.0), beta: float = 0.5) -> VectorField:
    """A unit cycle in (x, y) for every p, with a rotating (u, v) fibre of growth p - beta.

    x' = x (1 - r^2) - w1 y,  y' = w1 x + y (1 - r^2);
    u' = (p - beta) u - w2 v - u rho^2,  v' = w2 u + (p - beta) v - v rho^2.
    On the cycle u = v = 0 (T = 2 pi / w1) the multipliers are 1, exp(-2 T) and
    exp((p - beta) T) exp(+-i w2 T): a Neimark-Sacker point at p = beta.
    """

    def f(z, p):
        x, y, u, v = z
        r2, rho2, a = x ** 2 + y ** 2, u ** 2 + v ** 2, p - beta
        return np.stack([x * (1 - r2) - w1 * y, w1 * x + y * (1 - r2),
                         a * u - w2 * v - u * rho2, w2 * u + a * v - v * rho2])

    def dfdx(z, p):
        x, y, u, v = z
        r2, rho2, a = x ** 2 + y ** 2, u ** 2 + v ** 2, p - beta
        zero = np.zeros_like(x)
        return _jacobian([[1 - r2 - 2 * x ** 2, -w1 - 2 * x * y, zero, zero],
                          [w1 - 2 * x * y, 1 - r2 - 2 * y ** 2, zero, zero],
                          [zero, zero, a - rho2 - 2 * u ** 2, -w2 - 2 * u * v],
                          [zero, zero, w2 - 2 * u * v, a - rho2 - 2 * v ** 2]], z)

    def dfdp(z, p):
        x, y, u, v = z
        return np.stack([np.zeros_like(x), np.zeros_like(y), u, v])

    return VectorField(4, f, dfdx, dfdp, "neimark_sacker")


def period_doubling(beta: float = 0.5, b: float = -1.0) -> VectorField:
    """The unit cycle in (x, y) (w1 = 1) with a (u, v) fibre that turns by half a revolution per period.

    [u, v]' = ((a + b)/2) [u, v] + ((a - b)/2) S [u, v] + (1/2) J [u, v] - rho^2 [u, v],
    S = [[x, y], [y, -x]], J = [[0, -1], [1, 0]], a = p - beta.
    On the cycle (x, y) = (cos t, sin t), w = R(-t/2) [u, v] obeys w' = diag(a, b) w and
    R(pi) = -I after one period T = 2 pi: the fibre multipliers are -exp(a T), -exp(b T).
    A real multiplier crosses -1 at p = beta (period doubling).
    """
    half = 0.5

    def f(z, p):
        x, y, u, v = z
        r2, rho2, a = x ** 2 + y ** 2, u ** 2 + v ** 2, p - beta
        s, d = 0.5 * (a + b), 0.5 * (a - b)
        return np.stack([x * (1 - r2) - y, x + y * (1 - r2),
                         s * u + d * (x * u + y * v) - half * v - rho2 * u,
                         s * v + d * (y * u - x * v) + half * u - rho2 * v])

    def dfdx(z, p):
        x, y, u, v = z
        r2, rho2, a = x ** 2 + y ** 2, u ** 2 + v ** 2, p - beta
        s, d = 0.5 * (a + b), 0.5 * (a - b)
        zero = np.zeros_like(x)
        return _jacobian([[1 - r2 - 2 * x ** 2, -1 - 2 * x * y, zero, zero],
                          [1 - 2 * x * y, 1 - r2 - 2 * y ** 2, zero, zero],
                          [d * u, d * v, s + d * x - rho2 - 2 * u ** 2, d * y - half - 2 * u * v],
                          [-d * v, d * u, d * y + half - 2 * u * v, s - d * x - rho2 - 2 * v ** 2]], z)

    def dfdp(z, p):
        x, y, u, v = z
        # ds/dp = dd/dp = 1/2
        return np.stack([np.zeros_like(x), np.zeros_like(y),
                         0.5 * u + 0.5 * (x * u + y * v), 0.5 * v + 0.5 * (y * u - x * v)])

    return VectorField(4, f, dfdx, dfdp, "period_doubling")


ALL_SYSTEMS = {
    "fold_1d": fold_1d,
    "fold_2d": fold_2d,
    "pitchfork": pitchfork,
    "transcritical": transcritical,
    "hopf_supercritical": hopf_supercritical,
    "hopf_subcritical_quintic": hopf_subcritical_quintic,
    "hopf_twice": hopf_twice,
    "hopf_shear": hopf_shear,
    "hopf_close_pair": lambda: hopf_close_pair(1e-3),
    "two_pairs": lambda: two_pairs(1e-3),
    "van_der_pol": van_der_pol,
    "neimark_sacker": neimark_sacker,
    "period_doubling": period_doubling,
}
