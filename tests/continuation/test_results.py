"""Every branch and curve has the one result shape: special points, stops, closed, steps, to_dict."""

import dataclasses
import json

import numpy as np
import pytest
from textbook_systems import bautin

from shimmy.continuation import (ContinuationResult, Mesh, PeriodicOptions, PointKind, SpecialPoint, StopReason,
                                 cycle_curve, equilibrium_branch, hopf_curve, hopf_guess, periodic_branch)


@pytest.fixture(scope="module")
def results():
    """An equilibrium branch, the cycles born at its Hopf point, the Hopf curve and the fold curve of
    cycles of the Bautin normal form."""
    system = bautin()
    equilibria = equilibrium_branch(system.at(1.0), np.zeros(2), -1.0, p_range=(-1.0, 1.0))
    guess, shape = hopf_guess(np.zeros(2), 0.0, 1.0, np.array([1.0, -1j]), Mesh.uniform(20, 4), 0.0)
    cycles = periodic_branch(system.at(1.0), guess, p_range=(-1.0, 1.0), options=PeriodicOptions(ntst=20, ncol=4),
                             direction=shape)
    real = dataclasses.replace(system, smooth=False)  # its dfdx is real: no Lyapunov coefficient
    hopf = hopf_curve(real, np.zeros(2), np.array([0.0, 0.5]), box=((-1.0, 1.0), (-1.0, 1.0)))
    fold = next(s for s in cycles.special_points if s.kind == PointKind.FOLD_OF_CYCLES)
    folds = cycle_curve(system, PointKind.FOLD_OF_CYCLES, fold.solution, 1.0, box=((-2.0, 2.0), (-1.0, 1.0)))
    return {"equilibria": equilibria, "cycles": cycles, "hopf": hopf, "folds": folds}


@pytest.mark.parametrize("name", ["equilibria", "cycles", "hopf", "folds"])
def test_every_result_has_the_shared_shape_and_writes_json(results, name):
    result = results[name]
    assert isinstance(result, ContinuationResult)
    assert all(isinstance(s, SpecialPoint) and isinstance(s.kind, PointKind) for s in result.special_points)
    assert result.stop_reasons == [s.message for s in result.stops] and result.stop_reason
    data = json.loads(json.dumps(result.to_dict()))
    assert {"special_points", "stop_reasons", "steps", "closed"} <= data.keys()
    assert [s["kind"] for s in data["special_points"]] == [s.kind for s in result.special_points]


def test_a_hopf_curve_ends_on_the_box_both_ways(results):
    """The Hopf curve b1 = 0 of the Bautin form crosses the box in b2."""
    hopf = results["hopf"]
    np.testing.assert_allclose(hopf.p[:, 0], 0.0, atol=1e-9)
    assert hopf.p[:, 1].min() == pytest.approx(-1.0) and hopf.p[:, 1].max() == pytest.approx(1.0)
    assert [s.reason for s in hopf.stops] == [StopReason.BOUND, StopReason.BOUND]
    assert np.isnan(hopf.lyapunov).all() and hopf.to_dict()["lyapunov"] == [None] * len(hopf.p)


def test_stop_reasons_are_typed(results):
    assert [s.reason for s in results["equilibria"].stops] == [StopReason.BOUND]
    assert StopReason.ZERO_AMPLITUDE in [s.reason for s in results["folds"].stops]
    assert not any(r.closed for r in results.values())
