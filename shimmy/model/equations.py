"""Equations of motion of docs/model.md: right-hand side and analytic Jacobians.

The state is ``x = [psi, dpsi, delta, ddelta, lam]`` plus ``[psis, dpsis]`` with an NES.
All functions are vectorised: ``x`` may be one state ``(n,)`` or many columns ``(n, m)``,
with ``V`` and ``Fz`` scalars or arrays broadcastable to ``(m,)``. Jacobians come back
as ``(n, n)`` for one state and ``(m, n, n)`` for many (ready for batched ``eig``).

:func:`vector_field` and :func:`derivatives_at` (the analytic Jacobians in the state, V
and Fz) are plain arithmetic on one state, the one source of the equations: numba inlines
them into the integrator and into one compiled loop over columns of states, which
:func:`rhs`, :func:`jacobian`, :func:`parameter_jacobian` and, all four in one pass,
:func:`field_and_derivatives` run. States may be complex (the Jacobian is complex-analytic
away from the PD's |dpsi|; the stability module uses complex steps on it).

Model coefficients are packed once per (parameters, configuration) into a float
vector by :func:`model_coefficients`, indexed by the module constants below.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numba.extending import register_jitable

from . import nes as nes_device
from . import particle_damper
from .configurations import Configuration
from .parameters import Parameters

# Indices into the coefficient vector.
(I_PSI, IX, COS_PHI, SIN_PHI, E_EFF, K_PSI, C_PSI, K_DELTA, C_DELTA, K_A, ALPHA_M, C_LAM,
 L_G, H, L, K_LAM, K1, K3, I_NES, C_NES, NES_A, NES_RHO, NES_DELTA0, K_S, E_P,
 PD_N_R2, PD_R, PD_S12, PD_S1, PD_S32, PD_S2, PD_S3) = range(32)
N_COEFFICIENTS = 32


def effective_caster(R: float, phi: float, e: float) -> float:
    """e_eff = e cos(phi) + (R + e sin(phi)) tan(phi), in m."""
    return e * math.cos(phi) + (R + e * math.sin(phi)) * math.tan(phi)


@dataclass(frozen=True, eq=False)
class Model:
    """A configuration with its parameters, packed for the numerics.

    ``exact_nes`` switches the NES torque from the cubic fit (default) to the exact
    geometry M(a); the latter is undefined for |psi - psis| >= pi/6.
    """

    config: Configuration
    params: Parameters
    coefficients: np.ndarray
    exact_nes: bool = False

    @functools.cached_property  # read on every evaluation (the single-state path's check)
    def n_states(self) -> int:
        return self.config.n_states

    @functools.cached_property
    def flags(self) -> tuple[bool, bool, bool]:
        return self.config.has_nes, self.config.has_pd, self.exact_nes

    def rhs(self, x, V, Fz):
        return rhs(self, x, V, Fz)

    def jacobian(self, x, V, Fz):
        return jacobian(self, x, V, Fz)


def build_model(config: Configuration | str, params: Parameters | None = None,
                exact_nes: bool = False) -> Model:
    config = Configuration.parse(config)
    params = params if params is not None else Parameters()
    return Model(config, params, model_coefficients(config, params), bool(exact_nes))


def model_coefficients(config: Configuration, params: Parameters) -> np.ndarray:
    g, n, p = params.gear, params.nes, params.pd
    c = np.zeros(N_COEFFICIENTS)
    c[I_PSI] = g.Iz + (p.I_pd if config.has_pd else 0.0)
    c[IX] = g.Ix
    c[COS_PHI], c[SIN_PHI] = math.cos(g.phi), math.sin(g.phi)
    c[E_EFF] = effective_caster(g.R, g.phi, g.e)
    c[K_PSI], c[C_PSI], c[K_DELTA], c[C_DELTA] = g.k_psi, g.c_psi, g.k_delta, g.c_delta
    c[K_A], c[ALPHA_M], c[C_LAM] = g.k_a, g.alpha_m, g.c_lam
    c[L_G], c[H], c[L], c[K_LAM] = g.l_g, g.h, g.L, g.k_lam
    c[K1], c[K3] = nes_device.cubic_coefficients(n.r1, n.r2, n.r3, n.k_s, n.e_p)
    c[I_NES], c[C_NES] = n.I_nes, n.c_nes
    c[NES_A], c[NES_RHO], c[NES_DELTA0] = nes_device.geometry(n.r1, n.r2, n.r3)
    c[K_S], c[E_P] = n.k_s, n.e_p
    c[PD_N_R2], c[PD_R] = p.n * p.r * p.r, p.r
    c[PD_S12], c[PD_S1], c[PD_S32], c[PD_S2], c[PD_S3] = particle_damper.damping_coefficients(p).series
    return c


@register_jitable
def tyre_forces(lam, Fz, c):
    """Lateral tyre force F_lam (N) and self-aligning moment M_ka (N m) for deformation lam."""
    # tan(alpha) = lam / L, so atan(7 tan alpha) = atan(7 lam / L).
    w = np.arctan(7.0 * lam / c[L])
    force = c[K_LAM] * Fz * w * np.cos(0.95 * w)
    alpha = np.arctan(lam / c[L])
    alpha_m = c[ALPHA_M]
    aligning = (c[K_A] * alpha_m / np.pi * np.sin(np.pi * alpha / alpha_m) * Fz
                * (np.abs(alpha) <= alpha_m))
    return force, aligning


@register_jitable
def vector_field(psi, dpsi, delta, ddelta, lam, psis, dpsis, V, Fz, c, has_nes, has_pd, exact_nes):
    """Time derivatives of the seven states (the NES pair is zero without an NES)."""
    cos_phi = c[COS_PHI]
    e_eff = c[E_EFF]
    theta = psi * cos_phi
    sin_theta = np.sin(theta)
    cos_theta = np.cos(theta)
    force, aligning = tyre_forces(lam, Fz, c)
    torque = (c[C_PSI] * dpsi + c[K_PSI] * psi + aligning + e_eff * force
              + c[C_LAM] * dpsi * cos_phi / V - Fz * c[SIN_PHI] * e_eff * sin_theta)
    absorber = 0.0 * psi
    if has_nes:
        u = psi - psis
        if exact_nes:
            restoring = nes_device.torque_core(u, c[NES_A], c[NES_RHO], c[NES_DELTA0], c[K_S], c[E_P])
        else:
            restoring = c[K1] * u + c[K3] * u * u * u
        absorber = c[C_NES] * (dpsi - dpsis) + restoring
        torque = torque + absorber
    if has_pd:
        c_star = particle_damper.series_value(c[PD_R] * np.abs(dpsi), c[PD_S12], c[PD_S1], c[PD_S32],
                                              c[PD_S2], c[PD_S3])
        torque = torque + c[PD_N_R2] * c_star * dpsi
    psi_dd = -torque / c[I_PSI]
    delta_dd = -(c[C_DELTA] * ddelta + c[K_DELTA] * delta + c[L_G] * force * cos_theta * cos_phi
                 - Fz * e_eff * sin_theta) / c[IX]
    lam_d = (-(V / c[L]) * lam + V * sin_theta + c[L_G] * ddelta * np.cos(delta)
             + (e_eff - c[H]) * cos_theta * dpsi * cos_phi)
    psis_dd = absorber / c[I_NES]
    return dpsi, psi_dd, ddelta, delta_dd, lam_d, dpsis, psis_dd


@register_jitable
def tyre_derivatives(lam, Fz, c):
    """F_lam, dF_lam/dlam, M_ka and dM_ka/dlam (scalars or arrays, complex-safe)."""
    L_ = c[L]
    force, aligning = tyre_forces(lam, Fz, c)
    u = 7.0 * lam / L_
    w = np.arctan(u)
    dforce = c[K_LAM] * Fz * (7.0 / L_) * (np.cos(0.95 * w) - 0.95 * w * np.sin(0.95 * w)) / (1.0 + u * u)
    alpha = np.arctan(lam / L_)
    alpha_m = c[ALPHA_M]
    inside = np.abs(alpha.real) <= alpha_m
    dalpha = (1.0 / L_) / (1.0 + (lam / L_) ** 2)
    daligning = c[K_A] * np.cos(np.pi * alpha / alpha_m) * Fz * inside * dalpha
    return force, dforce, aligning, daligning


@register_jitable
def _pd_slope(dpsi, c):
    """d M_pd / d dpsi = n r^2 (3/2 s12 v^1/2 + 2 s1 v + 5/2 s32 v^3/2 + 3 s2 v^2 + 4 s3 v^3)."""
    v = c[PD_R] * np.abs(dpsi)
    root = np.sqrt(v)
    return c[PD_N_R2] * (1.5 * c[PD_S12] * root + 2.0 * c[PD_S1] * v + 2.5 * c[PD_S32] * v * root
                         + 3.0 * c[PD_S2] * v * v + 4.0 * c[PD_S3] * v ** 3)


@register_jitable
def derivatives_at(psi, dpsi, delta, ddelta, lam, psis, dpsis, V, Fz, c, has_nes, has_pd, exact_nes, J, dV, dFz):
    """Analytic d f / d x into J (n, n) and d f / d V, d f / d Fz into dV, dFz (n,) at one state
    (the arrays zeroed by the caller; entries outside the configuration's states untouched)."""
    cos_phi, e_eff = c[COS_PHI], c[E_EFF]
    theta = psi * cos_phi
    sin_theta, cos_theta = np.sin(theta), np.cos(theta)
    force, dforce, aligning, daligning = tyre_derivatives(lam, Fz, c)
    i_psi, ix = c[I_PSI], c[IX]

    J[0, 1] = 1.0
    J[1, 0] = (-c[K_PSI] + Fz * c[SIN_PHI] * e_eff * cos_theta * cos_phi) / i_psi
    J[1, 1] = (-c[C_PSI] - c[C_LAM] * cos_phi / V) / i_psi
    J[1, 4] = (-daligning - e_eff * dforce) / i_psi
    J[2, 3] = 1.0
    J[3, 0] = (c[L_G] * force * sin_theta * cos_phi * cos_phi + Fz * e_eff * cos_theta * cos_phi) / ix
    J[3, 2] = -c[K_DELTA] / ix
    J[3, 3] = -c[C_DELTA] / ix
    J[3, 4] = -c[L_G] * dforce * cos_theta * cos_phi / ix
    J[4, 0] = V * cos_theta * cos_phi - (e_eff - c[H]) * sin_theta * cos_phi * dpsi * cos_phi
    J[4, 1] = (e_eff - c[H]) * cos_theta * cos_phi
    J[4, 2] = -c[L_G] * ddelta * np.sin(delta)
    J[4, 3] = c[L_G] * np.cos(delta)
    J[4, 4] = -V / c[L]
    if has_pd:
        J[1, 1] -= _pd_slope(dpsi, c) / i_psi
    if has_nes:
        u = psi - psis
        if exact_nes:
            k_u = nes_device.stiffness_core(u, c[NES_A], c[NES_RHO], c[NES_DELTA0], c[K_S], c[E_P])
        else:
            k_u = c[K1] + 3.0 * c[K3] * u * u
        c_nes, i_nes = c[C_NES], c[I_NES]
        J[1, 0] -= k_u / i_psi
        J[1, 1] -= c_nes / i_psi
        J[1, 5] = k_u / i_psi
        J[1, 6] = c_nes / i_psi
        J[5, 6] = 1.0
        J[6, 0] = k_u / i_nes
        J[6, 1] = c_nes / i_nes
        J[6, 5] = -k_u / i_nes
        J[6, 6] = -c_nes / i_nes
    dV[1] = c[C_LAM] * dpsi * cos_phi / (V * V) / i_psi
    dV[4] = -lam / c[L] + sin_theta
    dFz[1] = (-aligning / Fz - e_eff * force / Fz + c[SIN_PHI] * e_eff * sin_theta) / i_psi
    dFz[3] = (-c[L_G] * (force / Fz) * cos_theta * cos_phi + e_eff * sin_theta) / ix


@njit(cache=True)
def _evaluate_columns(X, V, Fz, c, has_nes, has_pd, exact_nes, F, J, dV, dFz, want_f, want_derivatives):
    """f, d f / d x, d f / d V and d f / d Fz at every column of X (n, m) (V, Fz per column)."""
    n = X.shape[0]
    for k in range(X.shape[1]):
        zero = 0.0 * X[0, k]
        psis = X[5, k] if has_nes else zero
        dpsis = X[6, k] if has_nes else zero
        if want_f:
            d = vector_field(X[0, k], X[1, k], X[2, k], X[3, k], X[4, k], psis, dpsis, V[k], Fz[k], c,
                             has_nes, has_pd, exact_nes)
            for i in range(n):
                F[i, k] = d[i]
        if want_derivatives:
            derivatives_at(X[0, k], X[1, k], X[2, k], X[3, k], X[4, k], psis, dpsis, V[k], Fz[k], c,
                           has_nes, has_pd, exact_nes, J[k], dV[:, k], dFz[:, k])


@njit(cache=True)
def _evaluate_one(x, V, Fz, c, has_nes, has_pd, exact_nes, want_f, want_derivatives):
    """f (n,), d f / d x (n, n), d f / d V and d f / d Fz (n,) at one real state: the columns'
    loop on one column, without the packing the Python side of :func:`_evaluate` does."""
    n = x.shape[0]
    F = np.empty((n, 1))
    J = np.zeros((1, n, n))
    dV = np.zeros((n, 1))
    dFz = np.zeros((n, 1))
    _evaluate_columns(np.ascontiguousarray(x).reshape((n, 1)), np.full(1, V), np.full(1, Fz), c, has_nes, has_pd,
                      exact_nes, F, J, dV, dFz, want_f, want_derivatives)
    return F[:, 0], J[0], dV[:, 0], dFz[:, 0]


def _one_state(model: Model, x, V, Fz) -> bool:
    """The engine's commonest call: one real state at one speed and load (the compiled single-state
    path, without the columns' packing)."""
    return (type(x) is np.ndarray and x.ndim == 1 and x.dtype == np.float64 and x.shape[0] == model.n_states
            and isinstance(V, (float, int)) and isinstance(Fz, (float, int)))


def _check_states(model: Model, x) -> np.ndarray:
    x = np.asarray(x)
    if x.shape[0] != model.n_states:
        raise ValueError(f"state has {x.shape[0]} rows; configuration {model.config.value} "
                         f"has {model.n_states} states")
    return x


def _evaluate(model: Model, x, V, Fz, want_f: bool, want_derivatives: bool, plain: bool = False):
    """The compiled evaluation at states x (n,) or (n, ...), V and Fz broadcast against them:
    (shape, f (n, m), J (m, n, n), dV (n, m), dFz (n, m)), m the number of broadcast columns;
    ``plain``: the same arithmetic run as plain Python (see :func:`jacobian`)."""
    x = _check_states(model, x)
    n = model.n_states
    if x.ndim <= 2 and x.dtype == float and isinstance(V, (float, int)) and isinstance(Fz, (float, int)):
        shape = x.shape[1:]  # the engine's case: real states, one speed and load
        X = np.ascontiguousarray(x.reshape(n, -1))
        dtype = np.dtype(float)
        Vs, Fzs = np.full(X.shape[1], float(V)), np.full(X.shape[1], float(Fz))
    else:
        V, Fz = np.asarray(V), np.asarray(Fz)
        shape = np.broadcast(x[0], V, Fz).shape
        dtype = np.result_type(x, V, Fz, float)
        parts = np.broadcast_arrays(*x, V, Fz)
        X = np.array(parts[:n], dtype=dtype).reshape(n, -1)
        Vs, Fzs = (np.array(a, dtype=dtype).ravel() for a in parts[n:])
    m = X.shape[1]
    F = np.empty((n, m) if want_f else (n, 0), dtype)
    J = np.zeros((m, n, n) if want_derivatives else (0, n, n), dtype)
    dV = np.zeros((n, m) if want_derivatives else (n, 0), dtype)
    dFz = np.zeros_like(dV)
    columns = _evaluate_columns.py_func if plain else _evaluate_columns
    columns(X, Vs, Fzs, model.coefficients, *model.flags, F, J, dV, dFz, want_f, want_derivatives)
    return shape, F, J, dV, dFz


def rhs(model: Model, x, V, Fz):
    """f(x; V, Fz), shaped like x broadcast against V and Fz."""
    if _one_state(model, x, V, Fz):
        return _evaluate_one(x, float(V), float(Fz), model.coefficients, *model.flags, True, False)[0]
    shape, F, _, _, _ = _evaluate(model, x, V, Fz, True, False)
    return F.reshape((model.n_states,) + shape)


def jacobian(model: Model, x, V, Fz, *, plain: bool = False):
    """Analytic d f / d x: ``(n, n)`` for one state, ``(m, n, n)`` for columns.

    ``plain``: the same arithmetic run as plain Python instead of the compiled kernel, for a few
    evaluations where loading the compiled kernels (about 0.5 s in a fresh process) would cost more
    than computing (about 20 us an evaluation here): a Hopf scan of x = 0 as a command. At x = 0 it
    equals the compiled evaluation bit for bit; elsewhere to rounding (the transcendental functions
    are numpy's, not LLVM's)."""
    if _one_state(model, x, V, Fz) and not plain:
        return _evaluate_one(x, float(V), float(Fz), model.coefficients, *model.flags, False, True)[1]
    shape, _, J, _, _ = _evaluate(model, x, V, Fz, False, True, plain)
    return J.reshape(shape + J.shape[1:])


def parameter_jacobian(model: Model, x, V, Fz):
    """(d f / d V, d f / d Fz), each shaped like ``x``."""
    if _one_state(model, x, V, Fz):
        return _evaluate_one(x, float(V), float(Fz), model.coefficients, *model.flags, False, True)[2:]
    shape, _, _, dV, dFz = _evaluate(model, x, V, Fz, False, True)
    n = model.n_states
    return dV.reshape((n,) + shape), dFz.reshape((n,) + shape)


def field_and_derivatives(model: Model, x, V, Fz):
    """(f, d f / d x, d f / d V, d f / d Fz) in one compiled pass, shaped as :func:`rhs`,
    :func:`jacobian` and :func:`parameter_jacobian` give them."""
    if _one_state(model, x, V, Fz):
        return _evaluate_one(x, float(V), float(Fz), model.coefficients, *model.flags, True, True)
    shape, F, J, dV, dFz = _evaluate(model, x, V, Fz, True, True)
    n = model.n_states
    return (F.reshape((n,) + shape), J.reshape(shape + J.shape[1:]), dV.reshape((n,) + shape),
            dFz.reshape((n,) + shape))
