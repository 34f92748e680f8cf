"""Textbook vector fields with known bifurcations, in the form the continuation engine takes.

Every system is a :class:`shimmy.continuation.VectorField` with hand-derived Jacobians,
vectorised over columns: ``f(x, p)`` takes x of shape (n,) or (n, m); ``dfdx`` returns
(n, n) or (m, n, n). The known answers are stated next to each system.
"""

from __future__ import annotations

import math

import numpy as np

from shimmy.continuation import TwoParameterField, VectorField


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


def fold_near_torus(gap: float = 1e-3, w2: float = 0.37, rate: float = 10.0,
                    second_gap: float | None = None) -> VectorField:
    """A fold of cycles and a torus point ``gap`` apart in p on the same branch.

    x, y: r' = r (p + rho - rho^2), theta' = 1 (rho = r^2): cycles p = rho^2 - rho, a fold at
    p = -1/4 (rho = 1/2), period 2 pi; the large cycles (rho > 1/2) are stable in (x, y), the small
    ones unstable. Each fibre (u, v): growth rate (rho_ns - rho) and rotation w2, so its
    multipliers are exp(2 pi rate (rho_ns - rho)) exp(+-2 pi i w2): with rho_ns = 1/2 - sqrt(gap)
    a torus point on the small-cycle side at p = -1/4 + gap. Coming from the large cycles, one step
    across the fold takes three multipliers out of the unit circle at once, the real one nearest
    to it. ``second_gap`` adds a second fibre (rotation w2 + 0.1): a second torus point at
    p = -1/4 + second_gap.
    """
    gaps = [gap] + ([second_gap] if second_gap is not None else [])
    fibres = [(0.5 - math.sqrt(g), w2 + 0.1 * k) for k, g in enumerate(gaps)]
    n = 2 + 2 * len(fibres)

    def f(z, p):
        x, y = z[0], z[1]
        rho = x ** 2 + y ** 2
        G = p + rho - rho ** 2
        out = [G * x - y, x + G * y]
        for k, (rho_ns, w) in enumerate(fibres):
            u, v = z[2 + 2 * k], z[3 + 2 * k]
            a, s2 = rate * (rho_ns - rho), u ** 2 + v ** 2
            out += [a * u - w * v - s2 * u, w * u + a * v - s2 * v]
        return np.stack(out)

    def dfdx(z, p):
        x, y = z[0], z[1]
        rho = x ** 2 + y ** 2
        G, Gr = p + rho - rho ** 2, 1.0 - 2.0 * rho
        zero = 0.0 * x
        rows = [[G + 2 * x * x * Gr, -1.0 + 2 * x * y * Gr] + [zero] * (n - 2),
                [1.0 + 2 * x * y * Gr, G + 2 * y * y * Gr] + [zero] * (n - 2)]
        for k, (rho_ns, w) in enumerate(fibres):
            u, v = z[2 + 2 * k], z[3 + 2 * k]
            a, s2 = rate * (rho_ns - rho), u ** 2 + v ** 2
            ru = [-2 * rate * x * u, -2 * rate * y * u] + [zero] * (n - 2)
            rv = [-2 * rate * x * v, -2 * rate * y * v] + [zero] * (n - 2)
            ru[2 + 2 * k], ru[3 + 2 * k] = a - s2 - 2 * u * u, -w - 2 * u * v
            rv[2 + 2 * k], rv[3 + 2 * k] = w - 2 * u * v, a - s2 - 2 * v * v
            rows += [ru, rv]
        return _jacobian(rows, z)

    def dfdp(z, p):
        return np.concatenate([z[:2], 0.0 * z[2:]])

    return VectorField(n, f, dfdx, dfdp, "fold_near_torus")


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
    "fold_near_torus": lambda: fold_near_torus(1e-3, second_gap=2e-3),
}


# --------------------------------------------------------------------------- two-parameter cycles


def radial_two_parameter(G, G_rho, G_p, name: str) -> TwoParameterField:
    """x' = G x - y, y' = x + G y with G = G(rho, p1, p2), rho = x^2 + y^2.

    In polar form r' = r G(r^2, p), theta' = 1: cycles r^2 = rho0 with G(rho0, p) = 0, period
    2 pi, nontrivial multiplier exp(4 pi rho0 G_rho(rho0, p)): a fold of cycles where
    G = G_rho = 0. ``G_rho(rho, p)`` and ``G_p(rho, p)`` -> (dG/dp1, dG/dp2).
    """

    def f(z, p):
        x, y = z[0], z[1]
        g = G(x ** 2 + y ** 2, p)
        return np.stack([g * x - y, x + g * y])

    def dfdx(z, p):
        x, y = z[0], z[1]
        rho = x ** 2 + y ** 2
        g, gr = G(rho, p), G_rho(rho, p)
        return _jacobian([[g + 2 * x * x * gr, -1.0 + 2 * x * y * gr],
                          [1.0 + 2 * x * y * gr, g + 2 * y * y * gr]], z)

    def dfdp(z, p):
        x, y = z[0], z[1]
        g1, g2 = G_p(x ** 2 + y ** 2, p)
        return np.stack([np.stack([g1 * x, g1 * y]), np.stack([g2 * x, g2 * y])])

    return TwoParameterField(2, f, dfdx, dfdp, name)


def bautin() -> TwoParameterField:
    """The Bautin normal form G = b1 + b2 rho - rho^2 (l2 = -1).

    Hopf points of x = 0 at b1 = 0, a generalised Hopf point at (0, 0); for b2 > 0 the fold of
    cycles curve b1 = -b2^2 / 4 with rho0 = b2 / 2 (amplitude sqrt(b2 / 2)), ending at GH with
    zero amplitude.
    """
    return radial_two_parameter(lambda rho, p: p[0] + p[1] * rho - rho ** 2,
                                lambda rho, p: p[1] - 2.0 * rho,
                                lambda rho, p: (np.ones_like(rho), rho), "bautin")


def cusp_of_cycles() -> TwoParameterField:
    """G = b1 + b2 (rho - 1) - (rho - 1)^3: the fold curve (b1, b2) = (-2 s^3, 3 s^2) with
    rho0 = 1 + s, a cusp of cycles at (0, 0) on the unit cycle."""
    return radial_two_parameter(lambda rho, p: p[0] + p[1] * (rho - 1.0) - (rho - 1.0) ** 3,
                                lambda rho, p: p[1] - 3.0 * (rho - 1.0) ** 2,
                                lambda rho, p: (np.ones_like(rho), rho - 1.0), "cusp_of_cycles")


def torus_two_parameter(w2_0: float = 0.3, w2_slope: float = 0.1) -> TwoParameterField:
    """The neimark_sacker system with fibre growth a = p1 - p2^2 and rotation w2 = w2_0 + w2_slope p2.

    Unit cycle, T = 2 pi; fibre multipliers exp(a T) exp(+-i w2 T): the torus curve p1 = p2^2 with
    kappa = cos(2 pi w2); strong resonances where 2 pi w2 = 2 pi / k: R3 (w2 = 1/3) at
    p2 = (1/3 - w2_0) / w2_slope.
    """

    def parts(p):
        return p[0] - p[1] ** 2, w2_0 + w2_slope * p[1]

    def f(z, p):
        x, y, u, v = z
        a, w2 = parts(p)
        r2, rho2 = x ** 2 + y ** 2, u ** 2 + v ** 2
        return np.stack([x * (1 - r2) - y, x + y * (1 - r2), a * u - w2 * v - u * rho2, w2 * u + a * v - v * rho2])

    def dfdx(z, p):
        x, y, u, v = z
        a, w2 = parts(p)
        r2, rho2 = x ** 2 + y ** 2, u ** 2 + v ** 2
        zero = np.zeros_like(x)
        return _jacobian([[1 - r2 - 2 * x ** 2, -1 - 2 * x * y, zero, zero],
                          [1 - 2 * x * y, 1 - r2 - 2 * y ** 2, zero, zero],
                          [zero, zero, a - rho2 - 2 * u ** 2, -w2 - 2 * u * v],
                          [zero, zero, w2 - 2 * u * v, a - rho2 - 2 * v ** 2]], z)

    def dfdp(z, p):
        x, y, u, v = z
        zero = np.zeros_like(x)
        return np.stack([np.stack([zero, zero, u, v]),
                         np.stack([zero, zero, -2 * p[1] * u - w2_slope * v, -2 * p[1] * v + w2_slope * u])])

    return TwoParameterField(4, f, dfdx, dfdp, "torus_two_parameter")


def flip_two_parameter(b: float = -1.0) -> TwoParameterField:
    """The period_doubling system with a = p1 - p2^2: fibre multipliers -exp(a T), -exp(b T),
    T = 2 pi: the period-doubling curve p1 = p2^2."""
    one = period_doubling(beta=0.0, b=b)

    def f(z, p):
        return one.f(z, p[0] - p[1] ** 2)

    def dfdx(z, p):
        return one.dfdx(z, p[0] - p[1] ** 2)

    def dfdp(z, p):
        d = one.dfdp(z, p[0] - p[1] ** 2)
        return np.stack([d, -2.0 * p[1] * d])

    return TwoParameterField(4, f, dfdx, dfdp, "flip_two_parameter")


TWO_PARAMETER_SYSTEMS = {
    "bautin": bautin,
    "cusp_of_cycles": cusp_of_cycles,
    "torus_two_parameter": torus_two_parameter,
    "flip_two_parameter": flip_two_parameter,
}
