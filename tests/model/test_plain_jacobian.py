"""The Jacobian evaluated as plain Python (equations.jacobian(..., plain=True)): the compiled
kernel's arithmetic without loading it; equal to the compiled evaluation bit for bit at x = 0 (the
Hopf scan's only state) and to rounding elsewhere; the Hopf scan loads no compiled kernel."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from shimmy.model.configurations import Configuration
from shimmy.model.equations import build_model, jacobian
from shimmy.model.parameters import Parameters


@pytest.mark.parametrize("config", [c.value for c in Configuration])
def test_plain_equals_compiled_at_straight_rolling_bit_for_bit(config):
    model = build_model(config, Parameters())
    V = np.geomspace(1.0, 200.0, 23)
    for Fz in (1e4, 150e3, 537.5e3, 9e5):
        x = np.zeros((model.n_states, V.size))
        assert np.array_equal(jacobian(model, x, V, Fz, plain=True), jacobian(model, x, V, Fz))


@pytest.mark.parametrize("config", [c.value for c in Configuration])
def test_plain_equals_compiled_to_rounding_elsewhere(config):
    model = build_model(config, Parameters())
    rng = np.random.default_rng(7)
    scale = np.array([0.1, 2.0, 0.02, 0.5, 0.01, 0.05, 1.0])[:model.n_states]
    x = rng.normal(size=(model.n_states, 50)) * scale[:, None]
    V, Fz = rng.uniform(1, 200, 50), rng.uniform(1e4, 9e5, 50)
    plain, compiled = jacobian(model, x, V, Fz, plain=True), jacobian(model, x, V, Fz)
    np.testing.assert_allclose(plain, compiled, rtol=1e-13, atol=1e-13 * np.abs(compiled).max())
    complex_x = x + 1j * 1e-20 * rng.normal(size=x.shape)  # the complex steps of the Lyapunov coefficient
    np.testing.assert_allclose(jacobian(model, complex_x, V, Fz, plain=True), jacobian(model, complex_x, V, Fz),
                               rtol=1e-13, atol=1e-13 * np.abs(compiled).max())


def test_the_hopf_scan_loads_no_compiled_kernel():
    """In a fresh process: no compiled evaluation of the equations is loaded (0.5 s of a command)."""
    script = ("from shimmy.analyses.core.stability import hopf_points\n"
              "r = hopf_points('nes', 150e3)\n"
              "assert r.hopf_points, 'no Hopf point'\n"
              "from shimmy.model import equations\n"
              "loaded = [k for k in ('_evaluate_columns', '_evaluate_one') if getattr(equations, k).signatures]\n"
              "assert not loaded, loaded\n")
    subprocess.run([sys.executable, "-c", script], check=True, timeout=120)
