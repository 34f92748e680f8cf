"""Mode changes of stable cycles located on their branches (shimmy.analyses.diagrams.mode_changes).

Independent checks: the torsional share of the located cycle corrected again, with V held, on a mesh of
twice the intervals (the collocation's convergence: the threshold to 1e-6); the located change lies
between the diagram's two points whose modes differ; relocated at its own design it stays (to the
tolerance); relocated at a nearby design it is the change that design's own diagram locates (to the
meshes' difference, 1e-5 m/s), although it moved by metres per second; a map slice's interval ends
there. A change followed in the load (``follow_load``) ends on the change the diagram at the other load
locates (1e-5 m/s), each of its points stays where it is when relocated at its own load, and the curve
between two points lies within the chord tolerance of their chord (points relocated at the loads halfway).
"""

import dataclasses
import json

import numpy as np
import pytest

from shimmy.analyses.core.response import mode_of, torsional_share
from shimmy.analyses.diagrams.bifurcation import (STATE_SCALE, T_SCALE, V_SCALE, BifurcationOptions,
                                                  at_fixed_speed, bifurcation, gear_field)
from shimmy.analyses.diagrams.mode_changes import (CHORD_TOL, V_TOL, ModeChange, follow_load, locate_mode_changes,
                                                  relocate, share_of)
from shimmy.analyses.maps.map_slices import at_mode_changes, map_slice
from shimmy.continuation import ContinuationOptions
from shimmy.continuation.collocation import Mesh, PeriodicProblem
from shimmy.model.equations import build_model
from shimmy.model.parameters import Parameters

V_RANGE = (1.0, 150.0)
OPTIONS = BifurcationOptions(mesh_check=False)


@pytest.fixture(scope="module")
def nes():
    """nes at 288.4 kN: its cycle from the Hopf point turns from both to lateral near 24 m/s."""
    result = bifurcation("nes", 288.4e3, v_range=V_RANGE, options=OPTIONS)
    return result, locate_mode_changes(result)


def test_a_located_change_is_where_the_share_crosses_its_threshold(nes):
    result, changes = nes
    assert len(changes) == 1
    change = changes[0]
    assert change.threshold == 0.2 and 20.0 < change.V < 30.0
    lo, hi = sorted(change.bracket)
    assert lo < change.V < hi
    # the diagram's points either side: stable, modes differing
    b = next(b for b in result.branches if b.kind == "periodic" and b.raw is not None
             and any(np.isclose(b.raw.p, change.bracket[0])))
    raw = b.raw
    i = int(np.argmin(np.abs(raw.p - change.bracket[0])))
    gear = result.params.gear
    share = torsional_share(0.5 * (raw.x_max[:, 0] - raw.x_min[:, 0]), 0.5 * (raw.x_max[:, 2] - raw.x_min[:, 2]),
                            gear.k_psi, gear.k_delta)
    assert raw.stable[i] and raw.stable[i + 1] and mode_of(share[i]) != mode_of(share[i + 1])
    # the cycle at the change, corrected again with V held on a mesh of twice the intervals
    model = build_model(result.config, result.params)
    system = gear_field(model, result.Fz)
    scale = STATE_SCALE[:model.n_states]
    coarse = PeriodicProblem(system, Mesh(change.mesh, change.ncol), scale, T_SCALE, V_SCALE)
    fine = PeriodicProblem(system, coarse.adapted_mesh(change.u, 2 * coarse.mesh.ntst), scale, T_SCALE, V_SCALE)
    u = coarse.transfer(fine, change.u)
    fine.accept(u)
    point = at_fixed_speed(fine, u, ContinuationOptions())
    assert point is not None and point.u[-1] == pytest.approx(change.V, abs=1e-12)
    assert share_of(coarse, change.u, gear.k_psi, gear.k_delta) == pytest.approx(0.2, abs=1e-9)
    assert share_of(fine, point.u, gear.k_psi, gear.k_delta) == pytest.approx(0.2, abs=1e-6)


def test_a_change_relocated_at_its_own_design_stays(nes):
    result, changes = nes
    again = relocate(changes[0], result.config, result.params)
    assert again is not None and abs(again.V - changes[0].V) <= 10 * V_TOL
    back = ModeChange.from_dict(json.loads(json.dumps(changes[0].to_dict())))  # as a warm start stores it
    assert back.V == changes[0].V and np.array_equal(back.u, changes[0].u) and back.span == changes[0].span


@pytest.mark.parametrize("a_p", [0.85, 0.81])
def test_a_change_relocated_at_a_nearby_design_is_the_one_located_there(a_p):
    """pd at 306.7 kN: lowering the filling ratio from 0.9 moves its both -> lateral change by 1.5-4.7 m/s."""
    before = locate_mode_changes(bifurcation("pd", 306.7e3, v_range=V_RANGE, options=OPTIONS))
    params = Parameters().with_overrides({"a_p": a_p})
    after = locate_mode_changes(bifurcation("pd", 306.7e3, v_range=V_RANGE, params=params, options=OPTIONS))
    assert len(before) == len(after) == 1
    moved = relocate(before[0], "pd", params)
    assert moved is not None and abs(after[0].V - before[0].V) > 1.0
    assert moved.V == pytest.approx(after[0].V, abs=1e-5)


def test_a_change_followed_in_the_load_ends_on_the_change_located_there(nes):
    """nes: the both -> lateral change at 288.4 kN followed to 306.7 kN (where it lies 3.2 m/s lower) and on to
    405.6 kN (down to ~11.5 m/s, bending: the map's rows put it 8 m/s off before they followed it)."""
    result, changes = nes
    there = locate_mode_changes(bifurcation("nes", 306.7e3, v_range=V_RANGE, options=OPTIONS))
    assert [c.threshold for c in there] == [0.2]
    followed = follow_load(changes[0], 306.7e3, result.config, result.params)
    assert followed is not None and followed[-1].Fz == 306.7e3 and abs(followed[-1].V - changes[0].V) > 3.0
    assert followed[-1].V == pytest.approx(there[0].V, abs=1e-5)
    longer = follow_load(there[0], 405.6e3, result.config, result.params)
    assert longer is not None and 10.0 < longer[-1].V < 13.0
    gear = result.params.gear
    for before, point in zip([there[0], *longer[:-1]], longer, strict=True):
        assert before.Fz < point.Fz and point.threshold == 0.2
        again = relocate(point, result.config, result.params)  # a point of the curve: stays
        assert again is not None and abs(again.V - point.V) <= 10 * V_TOL
        model = build_model(result.config, result.params)
        problem = PeriodicProblem(gear_field(model, point.Fz), Mesh(point.mesh, point.ncol),
                                  STATE_SCALE[:model.n_states], T_SCALE, V_SCALE)
        assert share_of(problem, point.u, gear.k_psi, gear.k_delta) == pytest.approx(0.2, abs=1e-9)
        half = relocate(dataclasses.replace(before, Fz=0.5 * (before.Fz + point.Fz)), result.config, result.params)
        assert half is not None and abs(half.V - 0.5 * (before.V + point.V)) <= 3 * CHORD_TOL
    # a tighter chord: more points, each chord within twice it of the curve, the first step's too (its chord
    # is checked once the second step is taken: a midpoint put in)
    fine = follow_load(there[0], 405.6e3, result.config, result.params, chord=0.005)
    assert fine is not None and len(fine) > len(longer) and fine[-1].V == pytest.approx(longer[-1].V, abs=1e-6)
    for before, point in zip([there[0], *fine[:-1]], fine, strict=True):
        half = relocate(dataclasses.replace(before, Fz=0.5 * (before.Fz + point.Fz)), result.config, result.params)
        assert half is not None and abs(half.V - 0.5 * (before.V + point.V)) <= 2 * 0.005, (before.Fz, point.Fz)


def test_a_change_followed_where_its_curve_does_not_reach_gives_none(nes):
    """Followed down from 288.4 kN the change reaches 250 kN (35.2 m/s) but not 200 kN: a relocation there
    fails at every step down to MIN_STEP_SHARE of the way, and the follow says so (None), it does not return a point
    of another change."""
    result, changes = nes
    reached = follow_load(changes[0], 250e3, result.config, result.params)
    assert reached is not None and reached[-1].Fz == 250e3 and 30.0 < reached[-1].V < 40.0
    assert follow_load(changes[0], 200e3, result.config, result.params) is None
    assert follow_load(changes[0], changes[0].Fz, result.config, result.params) == []


def test_a_slice_interval_ends_at_the_located_change(nes):
    result, changes = nes
    s = map_slice("nes", result.Fz, params=result.params, v_range=V_RANGE, n_v=60, result=result)
    ends = {v for iv in s.intervals for v in (iv["V_start"], iv["V_end"])}
    assert changes[0].V in ends
    assert [c.V for c in s.mode_changes] == [changes[0].V]
    before = [iv for iv in s.intervals if iv["V_end"] == changes[0].V]
    after = [iv for iv in s.intervals if iv["V_start"] == changes[0].V]
    assert len(before) == len(after) == 1 and before[0]["type"] != after[0]["type"]
    assert s.lengths[before[0]["type"]] > 0 and s.lengths[after[0]["type"]] > 0


def _change(V: float, threshold: float, bracket: tuple[float, float]) -> ModeChange:
    return ModeChange(V, 3e5, threshold, np.zeros(2), 4, np.zeros(3), 0.1, bracket)


def test_ends_move_to_changes_of_their_own_threshold_and_never_past_each_other():
    """Synthetic slices on a fine grid of 0.1 m/s: an end goes only to a change whose threshold fits the
    types either side (Torsion | Both: 0.8, Both | Lateral: 0.2), and two ends never cross (checked where
    each stands once moved)."""
    fine = np.linspace(0.0, 20.0, 201)
    # a Torsion | Both end with only a 0.2 crossing near it: left where it was
    intervals = [{"type": "Torsion", "V_start": 0.0, "V_end": 10.05}, {"type": "Both", "V_start": 10.05, "V_end": 20.0}]
    out, used = at_mode_changes(intervals, [_change(10.9, 0.2, (10.0, 11.5))], [], fine)
    assert out == intervals and used == []
    out, used = at_mode_changes(intervals, [_change(10.9, 0.2, (10.0, 11.5)), _change(10.3, 0.8, (10.0, 11.5))],
                                [], fine)
    assert out[0]["V_end"] == out[1]["V_start"] == 10.3 and [c.V for c in used] == [10.3]
    # one step from 0.85 to 0.15: each end to its own threshold's change
    three = [{"type": "Torsion", "V_start": 0.0, "V_end": 10.25}, {"type": "Both", "V_start": 10.25, "V_end": 10.45},
             {"type": "Lateral", "V_start": 10.45, "V_end": 20.0}]
    out, used = at_mode_changes(three, [_change(10.1, 0.8, (9.5, 11.0)), _change(10.3, 0.2, (9.5, 11.0))], [], fine)
    assert [(iv["V_start"], iv["V_end"]) for iv in out] == [(0.0, 10.1), (10.1, 10.3), (10.3, 20.0)]
    # two changes that would make the ends cross: the second is left where it was
    crossing = [{"type": "Torsion", "V_start": 0.0, "V_end": 10.05}, {"type": "Both", "V_start": 10.05, "V_end": 10.55},
                {"type": "Lateral", "V_start": 10.55, "V_end": 20.0}]
    out, used = at_mode_changes(crossing, [_change(10.5, 0.8, (9.0, 10.6)), _change(10.2, 0.2, (10.18, 12.0))], [],
                                fine)
    assert all(iv["V_start"] <= iv["V_end"] for iv in out)
    assert all(a["V_end"] <= b["V_start"] for a, b in zip(out, out[1:]))
    assert len(used) == 1
