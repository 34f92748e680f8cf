"""Stability maps, the point classifier and the design metrics.

Independent checks: time simulations from several initial conditions (the attractors the map
claims are the ones the gear settles on), the eigenvalue scan (the pure-torsion region of
`original` below 250 kN is exactly where x = 0 is unstable, all Hopf points there being
supercritical), and the Hopf-curve continuation (lowest shimmy load).
"""

import math

import numpy as np
import pytest

from shimmy.analyses.diagrams.bifurcation import BifurcationOptions, bifurcation, cycle_at
from shimmy.analyses.maps.design_metrics import against_baseline, speed_metrics, torsion_area
from shimmy.errors import InvalidParameterError
from shimmy.analyses.core.executors import InlineExecutor
from shimmy.analyses.core.simulation import simulate
from shimmy.analyses.core.stability import hopf_points
from shimmy.analyses.maps import map_shading
from shimmy.analyses.core.response import shimmy_type
from shimmy.analyses.core.response import ResponseType
from shimmy.analyses.maps.map_slices import (SHIMMY_TYPES, TRIVIAL_LATERAL, TRIVIAL_PSI, attractors_at, attractors_on,
                                             classify, map_slice)
from shimmy.model.parameters import Parameters
from shimmy.analyses.maps.stability_map import stability_map, stability_maps

RESPONSE_OF_MODE = {"torsional": "Torsion", "lateral": "Lateral", "both": "Both"}


@pytest.fixture(scope="module")
def original_map():
    """original over V 1-200 m/s, Fz 10-900 kN on 12 slices (about 10 s on two workers)."""
    return stability_map("original", v_range=(1.0, 200.0), fz_range=(1.0e4, 9.0e5), resolution=12, n_v=60)


def _cycle(mode, amp=0.1):
    return {"kind": "limit cycle", "mode": mode, "max_psi": amp, "max_lateral": 0.01, "period": 0.1}


EQ = {"kind": "equilibrium", "mode": None, "max_psi": 0.0, "max_lateral": 0.0, "period": None}


@pytest.mark.parametrize("attractors, expected", [
    ([EQ], "Stable"),
    ([], "Stable"),
    ([_cycle("torsional")], "Torsion"),
    # subcritical: straight rolling stable, shimmy only after a large enough disturbance
    ([EQ, _cycle("torsional")], "Latent"),
    ([EQ, _cycle("lateral")], "Latent"),
    ([EQ, _cycle("torsional"), _cycle("lateral")], "Latent"),
    ([_cycle("lateral")], "Lateral"),
    ([_cycle("torsional"), _cycle("lateral")], "Bistable"),
    ([_cycle("lateral"), _cycle("torsional"), _cycle("both")], "Bistable"),
    ([_cycle("both")], "Both"),
    ([_cycle("torsional"), _cycle("both")], "Both"),
])
def test_shimmy_type_follows_the_definitions(attractors, expected):
    assert shimmy_type(attractors) == expected


def _settle(config, V, Fz, x0, t_end=100.0, rounds=5):
    """Simulate until the response is steady (slow transients with the particle damper)."""
    x = np.asarray(x0, float)
    for _ in range(rounds):
        run = simulate(config, V, Fz, x0=x, t_end=t_end)
        assert run.success, run.message
        if run.steady:
            return run
        x = run.states[:, -1]
    raise AssertionError(f"{config} at V = {V}, Fz = {Fz}: no steady response after {rounds * t_end} s")


def _matches(run, attractor) -> bool:
    if attractor["kind"] == "equilibrium":
        return run.response_type.value == "Stable"
    return (run.response_type.value == RESPONSE_OF_MODE[attractor["mode"]]
            and math.isclose(run.amplitude["psi"], attractor["max_psi"], rel_tol=0.03, abs_tol=1e-4)
            and math.isclose(run.amplitude["lateral"], attractor["max_lateral"], rel_tol=0.03, abs_tol=1e-4))


# One point inside each region of the maps (types as the classifier gives them; the first
# five are regions of the original map: low-load stable, A, F, D, low-speed high load).
SAMPLES = [
    ("original", 100.0, 100e3, "Stable"),
    ("original", 30.0, 150e3, "Torsion"),
    ("original", 180.0, 350e3, "Lateral"),
    ("original", 50.0, 350e3, "Bistable"),
    ("original", 10.0, 400e3, "Both"),
    ("original", 60.0, 650e3, "Bistable"),
    ("nes_pd", 30.0, 238.2e3, "Both"),
    ("nes_pd", 45.0, 238.2e3, "Lateral"),
    ("nes", 30.0, 150e3, "Torsion"),
    ("pd", 180.0, 850e3, "Lateral"),
    ("pd", 50.0, 350e3, "Lateral"),  # D: the particle damper leaves no stable torsional cycle
    ("original", 50.0, 850e3, "Bistable"),  # the torsional isola between two folds above ~720 kN
    ("nes", 50.0, 850e3, "Bistable"),
]


@pytest.mark.parametrize("config, V, Fz, expected", SAMPLES)
def test_classification_is_confirmed_by_simulation_from_several_starts(config, V, Fz, expected):
    """Each start (rest + 0.001 rad, a large torsion, a large lateral bending, and each stable
    cycle's own orbit) settles on one of the attractors the classifier lists; each listed cycle
    keeps a run started on it; the type is the expected one."""
    result = bifurcation(config, Fz, v_range=(1.0, 200.0), options=BifurcationOptions(mesh_check=False))
    answer = classify(config, V, Fz, result=result)
    assert answer["shimmy_type"] == expected, answer
    n = result.branches[0].V.size and (7 if "nes" in config else 5)
    starts = []
    for index, value in ((0, 0.001), (0, 0.2), (2, 0.05)):
        x0 = np.zeros(n)
        x0[index] = value
        starts.append(x0)
    attractors = answer["attractors"]
    for a in attractors:
        if a["kind"] == "limit cycle":
            orbit = cycle_at(result, a["branch"], V, max_psi=a["max_psi"])
            assert orbit["stable"]
            run = _settle(config, V, Fz, orbit["x0"])
            assert _matches(run, a), (a, run.response_type, run.amplitude)
    reached = []
    for x0 in starts:
        run = _settle(config, V, Fz, x0)
        hits = [a for a in attractors if _matches(run, a)]
        assert hits, (x0, run.response_type, run.amplitude, attractors)
        reached.append(hits[0]["kind"] + str(hits[0]["mode"]))
    if expected == "Bistable":  # both attractors are reached from the standard starts
        assert len(set(reached)) == 2, reached


def test_map_grid_and_the_classifier_agree(original_map):
    """The classified slices are the 12 asked for and those through regions they miss; at a
    slice load the classifier (the same computation) gives the map's answer."""
    m = original_map
    asked = np.linspace(1.0e4, 9.0e5, 12)
    assert all(np.min(np.abs(m.Fz - f)) < 1e-6 for f in asked) and list(m.Fz) == sorted(m.Fz)
    assert 12 <= m.Fz.size <= 12 + 16 and m.V.size == 60
    assert all(len(row) == 60 and set(row) <= set(SHIMMY_TYPES) for row in m.types)
    # Every type but Latent occurs on this map (see the simulation test for what each is; Latent: the next test).
    assert {t for row in m.shading for t in row} == set(SHIMMY_TYPES) - {"Latent"}
    for f, j in ((3, 10), (4, 40), (6, 5), (6, 45), (9, 30), (11, 59)):
        i = int(np.argmin(np.abs(m.Fz - asked[f])))
        answer = classify("original", float(m.V[j]), float(m.Fz[i]))
        assert answer["shimmy_type"] == m.types[i][j], (m.V[j], m.Fz[i])


def test_a_latent_region_where_straight_rolling_is_stable_beside_a_cycle_is_its_own_type():
    """pd at 306.7 kN (a default slice): from 1.4 to 3.7 m/s straight rolling is stable and a cycle with torsion and
    lateral bending both large is stable beside it (subcritical). The slice types it Latent; independent time
    histories agree: the standard start decays, a large yaw or lateral start ends on the diagram's cycle."""
    s = map_slice("pd", 306.7e3, params=Parameters(), v_range=(1.0, 200.0), n_v=100)
    latent = [(i["V_start"], i["V_end"]) for i in s.intervals if i["type"] == "Latent"]
    assert latent and latent[0][0] == pytest.approx(1.38, abs=0.05) and latent[0][1] == pytest.approx(3.66, abs=0.05)
    answer = classify("pd", 2.5, 306.7e3)
    assert answer["shimmy_type"] == "Latent"
    cycle = next(a for a in answer["attractors"] if a["kind"] != "equilibrium")
    assert {a["kind"] for a in answer["attractors"]} == {"equilibrium", "limit cycle"} and cycle["mode"] == "both"
    assert simulate("pd", 2.5, 306.7e3, t_end=120.0).response_type is ResponseType.STABLE
    for x0 in ([0.2, 0, 0, 0, 0], [0.0, 0, 0.04, 0, 0]):
        run = simulate("pd", 2.5, 306.7e3, x0=x0, t_end=120.0)
        assert run.response_type is ResponseType.BOTH and run.steady
        assert run.amplitude["psi"] == pytest.approx(cycle["max_psi"], rel=0.01)


def test_no_shimmy_below_the_lowest_hopf_point_and_the_minimum_load_is_it(original_map):
    m = original_map
    low = m.hopf.fz_minimum
    assert m.min_shimmy["source"] == "Hopf curve"
    assert m.min_shimmy_Fz == pytest.approx(low["Fz"])
    assert 59e3 < m.min_shimmy_Fz < 61e3  # the turning point of the torsional Hopf curve (59.95 kN)
    for Fz, row in zip(m.Fz, m.types, strict=True):
        if Fz < m.min_shimmy_Fz:
            assert set(row) == {"Stable"}
    # Just above it x = 0 is unstable somewhere and the slice is classified so.
    assert hopf_points("original", m.min_shimmy_Fz + 500.0).hopf_points


def test_fold_curves_end_at_the_generalised_hopf_points(original_map):
    m = original_map
    gh = m.hopf.gh_points
    assert len(gh) == 2 and len(m.fold_curves) == 2
    for g in gh:  # each GH point is the zero-amplitude end of a fold curve
        ends = [e for c in m.cycles["curves"] if c["kind"] == "LPC" for e in c["ends"] if e["kind"] == "ZA"]
        assert min(abs(e["V"] - g["V"]) / 10 + abs(e["Fz"] - g["Fz"]) / 1e5 for e in ends) < 2e-3
    for c in m.fold_curves:  # fold points lie above the GH loads: the subcritical side
        assert min(p["Fz"] for p in c) >= min(g["Fz"] for g in gh) - 1.0
    assert m.to_dict()["double_hopf_points"]


def test_every_fold_and_torus_point_of_a_slice_lies_on_a_drawn_curve(original_map):
    """The curves are continued in two parameters; their crossings of the loads of the slices
    asked for are located, and every LPC / NS point of those slices' diagrams is one of them (to
    1e-6 m/s). (The slices added through regions the others miss come after the curves.)"""
    m = original_map
    checked = 0
    marked = m.cycles["loads"]
    assert len(marked) == 12
    for s in m.slices:
        if min(abs(s.Fz - f) for f in marked) > 1e-6:
            continue
        crossings = {kind: [x["V"] for c in m.cycles["curves"] if c["kind"] == kind for x in c["crossings"]
                            if abs(x["Fz"] - s.Fz) < 1e-3] for kind in ("LPC", "NS")}
        for p in s.special_points:
            if p["kind"] in crossings:
                checked += 1
                assert crossings[p["kind"]], (s.Fz, p)
                assert min(abs(v - p["V"]) for v in crossings[p["kind"]]) < 1e-6, (s.Fz, p)
    assert checked >= 10


def test_torsion_area_of_original_equals_the_unstable_area_of_straight_rolling():
    """Below 250 kN every Hopf point of `original` is supercritical and every cycle torsional,
    so the pure-torsion region is where x = 0 is unstable: its area from 241 eigenvalue scans."""
    band = stability_map("original", v_range=(1.0, 200.0), fz_range=(1.0e4, 2.5e5), resolution=13, n_v=100,
                         executor=InlineExecutor())
    assert {t for row in band.types for t in row} == {"Stable", "Torsion"}
    loads = np.linspace(1.0e4, 2.5e5, 241)
    lengths = [sum(b - a for a, b in hopf_points("original", float(Fz), v_range=(1.0, 200.0)).unstable_intervals)
               for Fz in loads]
    reference = float(np.trapezoid(lengths, loads / 1e3))
    area = torsion_area(band)
    assert area["torsion_area"] == pytest.approx(reference, rel=0.01)
    assert area["band"]["Fz"] == [1.0e4, 2.5e5]
    assert 0.0 < area["torsion_area_fraction"] < 1.0


@pytest.mark.parametrize("config", ["pd", "nes_pd"])
def test_shimmy_speeds_with_the_particle_damper_reach_the_hopf_points(config):
    """With the PD the cycles grow like (V - V_H)^2: tiny near V_H, and still shimmy there."""
    m = speed_metrics(config, 150e3, n_v=200)
    assert m["shimmy_speed_range"] == pytest.approx(m["hopf_points"], abs=1e-12)


def test_speed_metrics_at_150_kN_match_the_hopf_points_and_the_diagram():
    m = speed_metrics("original", 150e3, n_v=200)
    low, high = m["shimmy_speed_range"]  # the interval ends are the located Hopf points
    assert [low, high] == pytest.approx(m["hopf_points"], abs=1e-12)
    assert [low, high] == pytest.approx([5.6118, 93.4290], abs=1e-4)
    assert [iv["type"] for iv in m["shimmy_intervals"]] == ["Torsion"]
    assert m["max_psi"] == pytest.approx(0.214823, abs=2e-6)


def test_changes_against_original_are_differences_and_ratios():
    base = {"min_shimmy_Fz": 60e3, "lateral_min_Fz": 220e3, "torsion_area": 100.0,
            "at_Fz": {"max_psi": 0.2, "shimmy_speed_range": [5, 90]}}
    m = {"min_shimmy_Fz": 75e3, "lateral_min_Fz": 231e3, "torsion_area": 80.0,
         "at_Fz": {"max_psi": 0.02, "shimmy_speed_range": None}}
    d = against_baseline(m, base)
    assert d["min_shimmy_Fz"]["change"] == pytest.approx(15e3) and d["min_shimmy_Fz"]["relative"] == 0.25
    assert d["lateral_min_Fz"]["change"] == pytest.approx(11e3) and d["lateral_min_Fz"]["relative"] == 0.05
    assert d["torsion_area"]["relative"] == pytest.approx(-0.2)
    assert d["max_psi"]["relative"] == pytest.approx(-0.9)
    assert d["shimmy_onset_V"]["change"] is None


def test_attractors_ignore_a_branch_run_on_along_x_equal_0():
    """With the particle damper a seeded branch can continue through its Hopf points along the
    trivial orbit; those points are x = 0, not cycles (nes_pd at 78.5 kN, V 1-14 m/s)."""
    result = bifurcation("nes_pd", 78461.5, v_range=(1.0, 200.0), options=BifurcationOptions(mesh_check=False))
    for V in (5.0, 60.0):
        found = attractors_at(result, V)
        assert [a["kind"] for a in found] == ["equilibrium"]
        assert simulate("nes_pd", V, 78461.5, t_end=60.0).response_type.value == "Stable"


def attractors_one_by_one(result, V):
    """The attractors at one speed, segment by segment in plain Python (the reference for the
    vectorised read-off on a whole grid)."""
    equilibrium = not any(a <= V <= b for a, b in result.hopf.unstable_intervals)
    found = [{"kind": "equilibrium", "mode": None, "max_psi": 0.0, "max_lateral": 0.0, "period": None,
              "branch": 0}] if equilibrium else []
    tol = 1e-7 * max(1.0, abs(V))
    for k, b in enumerate(result.branches):
        if b.kind != "periodic" or b.V.size < 2:
            continue
        pairs = [(i, i + 1) for i in range(b.V.size - 1)]
        if b.stop_reason.startswith("closed branch"):
            pairs.append((b.V.size - 1, 0))
        for i, j in pairs:
            v0, v1 = float(b.V[i]), float(b.V[j])
            if v0 == v1 or not min(v0, v1) - tol <= V <= max(v0, v1) + tol:
                continue
            f = min(max((V - v0) / (v1 - v0), 0.0), 1.0)
            near = i if f <= 0.5 else j
            stable = bool(b.stable[i]) if b.stable[i] == b.stable[j] else bool(b.stable[near])
            mode = b.mode[near] or b.mode[i] or b.mode[j]
            amp = float(b.max_psi[i] + f * (b.max_psi[j] - b.max_psi[i]))
            lateral = float(b.max_lateral[i] + f * (b.max_lateral[j] - b.max_lateral[i]))
            if not stable or mode is None or (amp <= 0.0 and lateral <= 0.0) \
                    or (equilibrium and amp <= TRIVIAL_PSI and lateral <= TRIVIAL_LATERAL):
                continue
            found.append({"kind": "limit cycle", "mode": mode, "max_psi": amp, "max_lateral": lateral,
                          "period": float(b.period[i] + f * (b.period[j] - b.period[i])), "branch": k})
    return found


@pytest.mark.parametrize("config, Fz", [("nes", 547e3), ("pd", 283e3), ("nes_pd", 78461.5)])
def test_attractors_on_a_grid_are_those_at_each_speed(config, Fz):
    """The read-off of a whole grid at once (closed loops, folds, Hopf ends, a branch run on along
    x = 0 among them) gives, speed by speed, the attractors of the plain one-speed read-off."""
    result = bifurcation(config, Fz, v_range=(1.0, 200.0), options=BifurcationOptions(mesh_check=False))
    ends = [float(v) for b in result.branches for v in b.V]
    grid = np.concatenate([np.linspace(1.0, 200.0, 991), ends])
    on_grid = attractors_on(result, grid)
    assert [attractors_one_by_one(result, float(V)) for V in grid] == on_grid
    assert sum(len(a) for a in on_grid) > grid.size  # cycles found, not only x = 0


@pytest.mark.parametrize("kwargs, field", [
    ({"resolution": 1}, "resolution"),
    ({"v_range": (50.0, 20.0)}, "v_max"),
    ({"fz_range": (1.0e3, 2.0e5)}, "fz_min"),
    ({"n_v": 5000}, "n_v"),
])
def test_bad_map_requests_name_the_field(kwargs, field):
    with pytest.raises(InvalidParameterError) as err:
        stability_map("original", **kwargs)
    assert err.value.field == field


def test_bad_requests_for_several_maps_name_the_field():
    with pytest.raises(InvalidParameterError) as err:
        stability_maps([])
    assert err.value.field == "configs"
    with pytest.raises(InvalidParameterError) as err:
        stability_maps(["original", "wing"])
    assert err.value.field == "config"


def test_maps_computed_together_are_the_maps_computed_one_by_one():
    """stability_maps runs several maps' units through one pool at once: each map is the one
    stability_map computes alone (its slices, curves and shading), and its elapsed time is its own."""
    plane = dict(v_range=(1.0, 200.0), fz_range=(1.0e4, 3.0e5), resolution=3, n_v=30)
    together = stability_maps(["original", "pd"], **plane)
    for smap, config in zip(together, ("original", "pd"), strict=True):
        alone = stability_map(config, executor=InlineExecutor(), **plane)
        assert smap.config.value == config
        assert smap.Fz.tolist() == alone.Fz.tolist()
        assert smap.shading == alone.shading and smap.types == alone.types
        assert len(smap.fold_curves) == len(alone.fold_curves) and len(smap.torus_curves) == len(alone.torus_curves)
        assert smap.min_shimmy_Fz == alone.min_shimmy_Fz
        assert 0.0 < smap.elapsed_s
    assert together[0].elapsed_s != together[1].elapsed_s


def test_classify_refuses_a_speed_outside_its_diagram():
    with pytest.raises(InvalidParameterError) as err:
        classify("original", 300.0, 150e3)
    assert err.value.field == "V"


@pytest.mark.slow
def test_shading_read_off_the_curves_agrees_with_the_classifier_away_from_boundaries(original_map):
    """The shading's rows lie between the slices; at points of uniform shading (5 x 5 cells) the
    classifier, which computes a diagram at that very load, gives the shaded type."""
    m = original_map
    grid = np.array(m.shading)
    assert grid.shape == (len(m.shading_Fz), len(m.V))
    picked = []
    for i in range(2, grid.shape[0] - 2, 17):
        for j in range(2, grid.shape[1] - 2, 7):
            block = grid[i - 2:i + 3, j - 2:j + 3]
            if (block == grid[i, j]).all():
                picked.append((i, j))
    picked = picked[::max(1, len(picked) // 8)][:8]
    assert len({grid[i, j] for i, j in picked}) >= 3
    for i, j in picked:
        V, Fz = float(m.V[j]), float(m.shading_Fz[i])
        assert classify("original", V, Fz)["shimmy_type"] == grid[i, j], (V, Fz)


class _Slice:
    def __init__(self, Fz, intervals):
        self.Fz, self.intervals = Fz, intervals


def test_shading_changes_only_at_the_curves_or_where_the_slices_change():
    """Read-off by construction: within one row, between two consecutive boundary crossings, the
    shading repeats the slice interval it is mapped from; a change of type inside an interval (a
    cycle's mode) moves linearly in Fz between the slices below and above."""
    # one boundary at V = 50 + Fz / 1e4 (moves with the load); Torsion left of it on both slices,
    # with a mode change (Both below 20 m/s on the lower slice, below 40 m/s on the upper one)
    curve = ("b", np.array([[50.0, 0.0], [150.0, 1.0e6]]))
    slices = [_Slice(1e5, [{"type": "Both", "V_start": 1.0, "V_end": 20.0},
                           {"type": "Torsion", "V_start": 20.0, "V_end": 60.0}]),
              _Slice(3e5, [{"type": "Both", "V_start": 1.0, "V_end": 40.0},
                           {"type": "Torsion", "V_start": 40.0, "V_end": 80.0}])]
    rows, fallbacks = map_shading.row_segments(slices, [curve], [2e5], (1.0, 200.0))
    edge = 50.0 + 2e5 / 1e4  # the boundary at the row's load: 70 m/s, between the slices' 60 and 80
    # the mode change at the same fraction of the interval [1, edge] as the slices' average
    f = 0.5 * ((20.0 - 1.0) / (60.0 - 1.0) + (40.0 - 1.0) / (80.0 - 1.0))
    change = 1.0 + f * (edge - 1.0)
    assert fallbacks == 0
    assert [t for _, _, t in rows[0]] == ["Both", "Torsion", "Stable"]
    assert rows[0][0][1] == pytest.approx(change) and rows[0][1][1] == pytest.approx(edge)
    V = np.linspace(1.0, 200.0, 400)
    row = np.array(map_shading.grid(rows, V)[0])
    assert (row[(V > change + 0.5) & (V < edge - 0.5)] == "Torsion").all() and (row[V > edge + 0.5] == "Stable").all()
    lengths = map_shading.measures(rows[0])
    assert lengths["Torsion"] == pytest.approx(edge - change) and lengths["Stable"] == pytest.approx(200.0 - edge)


def test_a_curves_located_crossings_are_vertices_of_its_polyline():
    """A curve Fz = 9e5 - 1e3 (V - 30)^2 N that turns at 900 kN, drawn as a polyline with a vertex every
    2.5 m/s (its chords cross a load up to ~0.1 m/s off the curve), its located crossings of two loads put
    in (two each, either side of the turn): the polyline crosses those loads exactly there, and every other
    load as before; a point far off every chord (another curve's) is left out."""
    V = np.arange(0.0, 60.01, 2.5)
    curve = np.column_stack([V, 9e5 - 1e3 * (V - 30.0) ** 2])
    loads = [6e5, 8.3e5]
    located = [(30.0 + side * np.sqrt((9e5 - F) / 1e3), F) for F in loads for side in (-1.0, 1.0)]
    for F in loads:
        chords = [x for x, _ in map_shading.crossings([("c", curve)], F)]
        wanted = sorted(v for v, f in located if f == F)
        assert len(chords) == 2 and 0.01 < max(abs(a - b) for a, b in zip(chords, wanted))  # the chords miss
    drawn = map_shading.with_points(curve, located + [(95.0, loads[0])])
    assert len(drawn) == len(curve) + len(located)
    for F in loads:
        assert [x for x, _ in map_shading.crossings([("c", drawn)], F)] == sorted(v for v, f in located if f == F)
    for F in (3e5, 7e5, 8.9e5):
        assert map_shading.crossings([("c", drawn)], F) == map_shading.crossings([("c", curve)], F)
    assert np.array_equal(map_shading.with_points(curve, []), curve)
    assert np.array_equal(map_shading.with_points(drawn, located), drawn)  # vertices already


def test_region_polygons_follow_the_rows_and_split_where_a_region_does():
    """A wedge of Torsion opening upwards between two boundaries, and above a load a Lateral
    island splitting it: the polygons' areas are the trapezoid rule over the rows, and each
    polygon is one type."""
    fz_rows = np.linspace(0.0, 1.0e5, 11)
    rows = []
    for Fz in fz_rows:
        w = 10.0 + Fz / 1e3  # Torsion on [100 - w, 100 + w]
        if Fz >= 5e4:  # a Lateral island in the middle, growing
            g = (Fz - 4e4) / 1e4
            rows.append([(0.0, 100 - w, "Stable"), (100 - w, 100 - g, "Torsion"), (100 - g, 100 + g, "Lateral"),
                         (100 + g, 100 + w, "Torsion"), (100 + w, 300.0, "Stable")])
        else:
            rows.append([(0.0, 100 - w, "Stable"), (100 - w, 100 + w, "Torsion"), (100 + w, 300.0, "Stable")])
    polygons = map_shading.polygons(rows, fz_rows)
    for t in ("Stable", "Torsion", "Lateral"):
        area = sum(map_shading.polygon_area(p) for p in polygons if p["type"] == t)
        lengths = [sum(b - a for a, b, u in r if u == t) for r in rows]
        assert area == pytest.approx(float(np.trapezoid(lengths, fz_rows)), rel=0.02), t
    torsion = [p for p in polygons if p["type"] == "Torsion"]
    assert len(torsion) == 3  # the wedge below the split, then its two arms


def _inside(polygon, V, Fz):
    """Ray casting: whether (V, Fz) lies inside a polygon ring."""
    xs, ys = polygon["V"], polygon["Fz"]
    hit = False
    for k in range(len(xs)):
        x0, y0, x1, y1 = xs[k - 1], ys[k - 1], xs[k], ys[k]
        if (y0 > Fz) != (y1 > Fz) and V < x0 + (Fz - y0) * (x1 - x0) / (y1 - y0):
            hit = not hit
    return hit


@pytest.mark.parametrize("rows", [
    # a Torsion region ending between the rows between two other types (Both, Lateral)
    [[(0, 40, "Both"), (40, 60, "Torsion"), (60, 100, "Lateral")], [(0, 45, "Both"), (45, 100, "Lateral")]],
    # two regions starting in one gap, and one ending at the row's edge
    [[(0, 10, "Stable"), (10, 50, "Torsion"), (50, 100, "Lateral")],
     [(0, 30, "Torsion"), (30, 35, "Both"), (35, 45, "Bistable"), (45, 100, "Lateral")]],
    # a split and a merge with a different type in the middle, regions ending and starting in one gap
    [[(0, 20, "Stable"), (20, 30, "Both"), (30, 70, "Stable"), (70, 100, "Torsion")],
     [(0, 40, "Stable"), (40, 50, "Lateral"), (50, 60, "Stable"), (60, 100, "Bistable")]],
])
def test_region_polygons_cover_every_point_once(rows):
    """Between two rows the polygons tile the strip: every point lies in exactly one polygon, of
    the type of a segment of a row next to it."""
    polygons = map_shading.polygons(rows, [0.0, 1.0])
    rng = np.random.default_rng(3)
    for V, Fz in zip(rng.uniform(0.01, 99.99, 2000), rng.uniform(0.01, 0.99, 2000), strict=True):
        hits = [p["type"] for p in polygons if _inside(p, V, Fz)]
        assert len(hits) == 1, (V, Fz, hits)
        assert hits[0] in {t for row in rows for _, _, t in row}


def test_shading_is_on_the_right_side_of_every_hopf_curve(original_map):
    """Independent of the read-off: on every shading row, x = 0 is unstable (eigenvalues at that
    very load) exactly where the shading says shimmy of some kind is possible from small
    disturbances, up to one grid cell: no cell is Stable where x = 0 is unstable, and below the
    GH loads (every Hopf point supercritical) no cell is unstable-free and shaded."""
    m = original_map
    cell = float(m.V[1] - m.V[0])
    gh_low = min(g["Fz"] for g in m.hopf.gh_points)
    checked = 0
    for Fz, row in zip(m.shading_Fz[::6], m.shading[::6], strict=True):
        unstable = hopf_points("original", float(Fz), v_range=(1.0, 200.0)).unstable_intervals
        for V, t in zip(m.V, row, strict=True):
            inside = any(a + cell < V < b - cell for a, b in unstable)
            outside = all(V < a - cell or V > b + cell for a, b in unstable)
            if inside:
                assert t != "Stable", (Fz, V, t)
                checked += 1
            elif outside and Fz < gh_low:
                assert t == "Stable", (Fz, V, t)
                checked += 1
    assert checked > 500


def test_region_polygons_tile_the_shading(original_map):
    """Each type's polygons have the area of its row measures (trapezoidal in Fz); a point in
    the middle of each polygon has the polygon's type in the shading."""
    m = original_map
    data = m.to_dict()
    assert data["regions"] and data["methods"]["regions"]
    rows = np.asarray(m.shading_Fz) / 1e3
    for t in SHIMMY_TYPES:
        polygons = [p for p in m.regions if p["type"] == t]
        area = sum(map_shading.polygon_area(p) for p in polygons) / 1e3
        lengths = np.array([r.get(t, 0.0) for r in m.shading_lengths])
        assert area == pytest.approx(float(np.trapezoid(lengths, rows)), rel=0.02, abs=50.0), t
    for p in m.regions:
        lo, hi, Fz = _widest_row(p)
        if hi - lo < 3 * (m.V[1] - m.V[0]):
            continue
        V = 0.5 * (lo + hi)
        assert m.type_at(V, Fz) == p["type"], (p["type"], V, Fz)


def _widest_row(polygon):
    """(V_low, V_high, Fz) of the widest row of a region polygon (its rows go up the low-speed
    edge and back down the high-speed edge)."""
    V, Fz = polygon["V"], polygon["Fz"]
    rows = len(V) // 2
    r = max(range(rows), key=lambda k: V[len(V) - 1 - k] - V[k])
    return V[r], V[len(V) - 1 - r], Fz[r]


def _reached(config, V, Fz):
    """Response types reached from the three standard starts (psi = 0.001 rad, psi = 0.2 rad,
    l_g delta = 0.1 m)."""
    n = 7 if "nes" in config else 5
    out = set()
    for index, value in ((0, 0.001), (0, 0.2), (2, 0.05)):
        x0 = np.zeros(n)
        x0[index] = value
        out.add(_settle(config, V, Fz, x0).response_type.value)
    return out


@pytest.mark.slow
def test_every_region_of_the_map_is_confirmed_by_simulation_from_three_starts(original_map):
    """In the middle of the widest row of each region polygon (if 3 cells wide), the types reached by time
    simulation from the three standard starts are what the region's type says."""
    m = original_map
    cell = float(m.V[1] - m.V[0])
    checked = set()
    for p in m.regions:
        lo, hi, Fz = _widest_row(p)
        if hi - lo < 3 * cell or Fz < 2e4:
            continue
        V = 0.5 * (lo + hi)
        reached = _reached("original", V, Fz)
        t = p["type"]
        if t == "Stable":
            assert reached == {"Stable"}, (V, Fz, reached)
        elif t in ("Torsion", "Lateral"):
            other = "Lateral" if t == "Torsion" else "Torsion"
            assert t in reached and other not in reached, (t, V, Fz, reached)
        elif t == "Bistable":
            assert {"Torsion", "Lateral"} <= reached, (V, Fz, reached)
        elif t == "Latent":
            assert "Stable" in reached and len(reached) > 1, (V, Fz, reached)
        else:
            assert "Both" in reached, (V, Fz, reached)
        checked.add(t)
    assert checked == set(SHIMMY_TYPES) - {"Latent"}, checked  # original has no Latent region (pd's: its own test)


@pytest.mark.parametrize("upper, inside", [
    # Both inside Torsion on the lower slice only: it narrows to its centre at the upper slice
    ([{"type": "Torsion", "V_start": 1.0, "V_end": 80.0}], True),
    # Both between Torsion and Lateral on the lower slice only: it narrows to the upper slice's breakpoint
    ([{"type": "Torsion", "V_start": 1.0, "V_end": 30.0}, {"type": "Lateral", "V_start": 30.0, "V_end": 80.0}],
     False),
])
def test_a_mode_piece_one_slice_lacks_narrows_linearly_instead_of_a_staircase(upper, inside):
    """A cycle's mode (here Both) that the lower slice shows inside an interval and the upper does not:
    the rows between the slices narrow it linearly in Fz (its edges straight lines in (V, Fz)), not
    the lower slice's pieces up to halfway and the upper's above (a staircase edge)."""
    curve = ("b", np.array([[50.0, 0.0], [150.0, 1.0e6]]))  # the interval's end: V = 50 + Fz / 1e4
    lower = [{"type": "Torsion", "V_start": 1.0, "V_end": 20.0}, {"type": "Both", "V_start": 20.0, "V_end": 40.0}]
    lower += [{"type": "Torsion" if inside else "Lateral", "V_start": 40.0, "V_end": 60.0}]
    slices = [_Slice(1e5, lower), _Slice(3e5, upper)]
    loads = [1.5e5, 2e5, 2.5e5]
    rows, fallbacks = map_shading.row_segments(slices, [curve], loads, (1.0, 200.0))
    assert fallbacks == 0
    widths = []
    for Fz, row in zip(loads, rows, strict=True):
        both = [(a, b) for a, b, t in row if t == "Both"]
        assert len(both) == 1
        widths.append(both[0][1] - both[0][0])
        edge = 50.0 + Fz / 1e4
        assert row[-2][1] == pytest.approx(edge) and row[-1][2] == "Stable"
    # the Both piece's share of [1, edge] shrinks linearly: 3/4, 1/2, 1/4 of the lower slice's (20/59)
    shares = [w / (50.0 + Fz / 1e4 - 1.0) for w, Fz in zip(widths, loads, strict=True)]
    assert shares == pytest.approx([0.75 * 20 / 59, 0.5 * 20 / 59, 0.25 * 20 / 59], rel=1e-9)
    # where it narrows to: its own centre (19 + 39) / 2 / 59 of the interval inside one type, the upper
    # slice's breakpoint (29 / 79) between two
    target = 29 / 59 if inside else 29 / 79
    lower_mid = 29 / 59
    for Fz, row in zip(loads, rows, strict=True):
        w = (Fz - 1e5) / 2e5
        (a, b), = [(a, b) for a, b, t in row if t == "Both"]
        mid = (0.5 * (a + b) - 1.0) / (50.0 + Fz / 1e4 - 1.0)
        assert mid == pytest.approx(lower_mid + w * (target - lower_mid), rel=1e-9)



def test_a_mode_change_joined_by_a_link_is_read_off_the_link_between_the_slices():
    """Two slices with a change from Both to Torsion at 20 and 40 m/s inside the interval below a curve, and
    the change's curve between them (a link) bending to 25 m/s halfway: the rows put the change on the link
    (interpolated along its polyline), not on the straight line between the slices (30 m/s halfway)."""
    curve = ("b", np.array([[50.0, 0.0], [150.0, 1.0e6]]))
    slices = [_Slice(1e5, [{"type": "Both", "V_start": 1.0, "V_end": 20.0},
                           {"type": "Torsion", "V_start": 20.0, "V_end": 60.0}]),
              _Slice(3e5, [{"type": "Both", "V_start": 1.0, "V_end": 40.0},
                           {"type": "Torsion", "V_start": 40.0, "V_end": 80.0}])]
    link = np.array([[20.0, 1e5], [25.0, 2e5], [40.0, 3e5]])
    loads = [1.5e5, 2e5, 2.5e5]
    rows, fallbacks = map_shading.row_segments(slices, [curve], loads, (1.0, 200.0), [link])
    assert fallbacks == 0
    for Fz, row in zip(loads, rows, strict=True):
        assert [t for _, _, t in row] == ["Both", "Torsion", "Stable"]
        assert row[0][1] == pytest.approx(float(np.interp(Fz, link[:, 1], link[:, 0])), rel=1e-12)
        assert row[1][1] == pytest.approx(50.0 + Fz / 1e4)  # the curve's crossing, as without the link
    # a link with neither end at the slices' changes is not this change's: the straight line again
    other = np.array([[21.0, 1e5], [25.0, 2e5], [41.0, 3e5]])
    plain, _ = map_shading.row_segments(slices, [curve], loads, (1.0, 200.0))
    assert map_shading.row_segments(slices, [curve], loads, (1.0, 200.0), [other])[0] == plain
    # one followed down from the upper slice's change that ends elsewhere (open): read off it all the same
    down = np.array([[21.0, 1e5], [25.0, 2e5], [40.0, 3e5]])
    rows, _ = map_shading.row_segments(slices, [curve], loads, (1.0, 200.0), [down])
    assert [row[0][1] for row in rows] == pytest.approx([np.interp(Fz, down[:, 1], down[:, 0]) for Fz in loads])


def test_a_change_followed_into_a_row_of_another_region_is_read_off_its_link():
    """The lower slice's change (Both to Torsion at 20 m/s) has a link up to 30 m/s at the upper slice's load,
    where a second curve has entered the interval (above 1.6e5 N): the rows below 1.6e5 N lie in a region only
    the lower slice crosses and read it alone, putting the change where the link crosses them (22.5 m/s at
    1.5e5 N; the slice's own fraction of the interval put it at 20); the rows above read the upper slice
    alone, and put its change on the link too (24 m/s at 1.8e5 N, where its fraction of [1, 45] put it at 30).
    A link whose end is not at a slice's change is not used."""
    edge = ("b", np.array([[50.0, 0.0], [50.0, 1.0e6]]))
    inner = ("c", np.array([[45.0, 1.6e5], [45.0, 1.0e6]]))
    slices = [_Slice(1e5, [{"type": "Both", "V_start": 1.0, "V_end": 20.0},
                           {"type": "Torsion", "V_start": 20.0, "V_end": 50.0}]),
              _Slice(3e5, [{"type": "Both", "V_start": 1.0, "V_end": 30.0},
                           {"type": "Torsion", "V_start": 30.0, "V_end": 45.0}])]
    link = np.array([[20.0, 1e5], [30.0, 3e5]])
    loads = [1.5e5, 1.8e5, 2.5e5]
    rows, _ = map_shading.row_segments(slices, [edge, inner], loads, (1.0, 200.0), [link])
    plain, _ = map_shading.row_segments(slices, [edge, inner], loads, (1.0, 200.0))
    assert plain[0][0] == (1.0, pytest.approx(20.0), "Both")
    assert rows[0] == [(1.0, pytest.approx(22.5), "Both"), (pytest.approx(22.5), 50.0, "Torsion"),
                       (50.0, 200.0, "Stable")]
    for Fz, row, old in zip(loads[1:], rows[1:], plain[1:], strict=True):
        assert old[0] == (1.0, pytest.approx(30.0), "Both")
        V = float(np.interp(Fz, link[:, 1], link[:, 0]))
        assert row == [(1.0, pytest.approx(V), "Both"), (pytest.approx(V), 45.0, "Torsion")] + old[2:]
    # a link from elsewhere (neither end at a slice's change): no row takes it
    moved = np.array([[20.5, 1e5], [30.5, 3e5]])
    assert map_shading.row_segments(slices, [edge, inner], loads, (1.0, 200.0), [moved])[0] == plain


def test_a_change_followed_into_a_region_its_slice_does_not_cross_splits_the_rows_there():
    """The upper slice's Both | Lateral change (30 m/s) followed down to the lower load (open: the lower slice has
    no Lateral piece, its change's curve ends at 45 m/s inside the lower slice's Both), while a second curve
    enters the interval only above 1.6e5 N: the rows below 1.6e5 N lie in a region only the lower slice crosses
    (all Both there) and take the change where its link crosses them (41.25 m/s at 1.5e5 N), Both left of it
    and Lateral right of it, as on the upper slice; before, the row was Both throughout (nes_pd at rho_p
    8580 kg/m^3 between 233.7 and 248.7 kN: 8 cells of the warm map off the cold map's edges). A link whose
    upper end is not at a change of the upper slice splits nothing."""
    edge = ("b", np.array([[100.0, 0.0], [100.0, 1.0e6]]))
    inner = ("c", np.array([[60.0, 1.6e5], [60.0, 1.0e6]]))
    slices = [_Slice(1e5, [{"type": "Both", "V_start": 1.0, "V_end": 100.0}]),
              _Slice(3e5, [{"type": "Both", "V_start": 1.0, "V_end": 30.0},
                           {"type": "Lateral", "V_start": 30.0, "V_end": 60.0},
                           {"type": "Torsion", "V_start": 60.0, "V_end": 100.0}])]
    link = np.array([[45.0, 1e5], [30.0, 3e5]])
    loads = [1.5e5, 2.5e5]
    rows, _ = map_shading.row_segments(slices, [edge, inner], loads, (1.0, 200.0), [link])
    plain, _ = map_shading.row_segments(slices, [edge, inner], loads, (1.0, 200.0))
    assert plain[0] == [(1.0, 100.0, "Both"), (100.0, 200.0, "Stable")]
    assert rows[0] == [(1.0, pytest.approx(41.25), "Both"), (pytest.approx(41.25), 100.0, "Lateral"),
                       (100.0, 200.0, "Stable")]
    V = float(np.interp(2.5e5, link[:, 1], link[:, 0]))  # above: read off the upper slice's change's link
    assert rows[1][:2] == [(1.0, pytest.approx(V), "Both"), (pytest.approx(V), 60.0, "Lateral")]
    elsewhere = np.array([[45.0, 1e5], [31.0, 3e5]])
    assert map_shading.row_segments(slices, [edge, inner], loads, (1.0, 200.0), [elsewhere])[0][0] == plain[0]


def test_changes_crossing_a_row_read_off_one_slice_are_all_put_in_whatever_their_order():
    """As above with two changes of the upper slice followed down into a row whose region only the lower slice
    (all Torsion there) crosses: Both | Lateral (30 m/s, down to 40) and Lateral | Torsion (60 m/s, down to 70)
    cross the row at 37.5 and 67.5 m/s; the row is Both, Lateral, Torsion, with the links given in either
    order (the first split makes the part the other falls in one of its types). A link whose end at the lower
    slice is a change of that slice is its own (read by the slice's breakpoints), not split in here."""
    edge = ("b", np.array([[100.0, 0.0], [100.0, 1.0e6]]))
    inner = ("c", np.array([[80.0, 1.6e5], [80.0, 1.0e6]]))
    slices = [_Slice(1e5, [{"type": "Torsion", "V_start": 1.0, "V_end": 100.0}]),
              _Slice(3e5, [{"type": "Both", "V_start": 1.0, "V_end": 30.0},
                           {"type": "Lateral", "V_start": 30.0, "V_end": 60.0},
                           {"type": "Torsion", "V_start": 60.0, "V_end": 100.0}])]
    left, right = np.array([[40.0, 1e5], [30.0, 3e5]]), np.array([[70.0, 1e5], [60.0, 3e5]])
    for links in ([left, right], [right, left]):
        rows, _ = map_shading.row_segments(slices, [edge, inner], [1.5e5], (1.0, 200.0), links)
        assert rows[0] == [(1.0, pytest.approx(37.5), "Both"), (pytest.approx(37.5), pytest.approx(67.5), "Lateral"),
                           (pytest.approx(67.5), 100.0, "Torsion"), (100.0, 200.0, "Stable")]
    lower = [{"type": "Both", "V_start": 1.0, "V_end": 40.0}, {"type": "Torsion", "V_start": 40.0, "V_end": 100.0}]
    own = [_Slice(1e5, lower), slices[1]]  # the left link ends on the lower slice's own change now
    rows, _ = map_shading.row_segments(own, [edge, inner], [1.5e5], (1.0, 200.0), [left])
    plain, _ = map_shading.row_segments(own, [edge, inner], [1.5e5], (1.0, 200.0))
    assert [t for _, _, t in rows[0]] == [t for _, _, t in plain[0]] == ["Both", "Torsion", "Stable"]


def test_a_mode_piece_ends_where_its_open_link_meets_its_other_end():
    """Both between Torsion and Lateral on the lower slice only; its right end's change followed up (an open
    link: the upper slice has no such change) runs left, from 40 m/s to 10 m/s at the upper load: the rows put
    that end on the link, and the piece vanishes at the row where the link has passed its left end (which
    narrows linearly, as without a link)."""
    curve = ("b", np.array([[50.0, 0.0], [150.0, 1.0e6]]))
    lower = [{"type": "Torsion", "V_start": 1.0, "V_end": 20.0}, {"type": "Both", "V_start": 20.0, "V_end": 40.0},
             {"type": "Lateral", "V_start": 40.0, "V_end": 60.0}]
    upper = [{"type": "Torsion", "V_start": 1.0, "V_end": 30.0}, {"type": "Lateral", "V_start": 30.0, "V_end": 80.0}]
    slices = [_Slice(1e5, lower), _Slice(3e5, upper)]
    link = np.array([[40.0, 1e5], [10.0, 3e5]])
    loads = [1.5e5, 2e5, 2.5e5]
    rows, _ = map_shading.row_segments(slices, [curve], loads, (1.0, 200.0), [link])
    plain, _ = map_shading.row_segments(slices, [curve], loads, (1.0, 200.0))
    for Fz, row, old in zip(loads, rows, plain, strict=True):
        (a, b), = [(a, b) for a, b, t in old if t == "Both"]
        on_link = float(np.interp(Fz, link[:, 1], link[:, 0]))
        both = [(x, y) for x, y, t in row if t == "Both"]
        if on_link > a:  # the link's end is right of the left end: the piece from there to the link
            assert both == [(pytest.approx(a), pytest.approx(on_link))]
        else:  # passed it: gone, Torsion meets Lateral where the left end was
            assert both == [] and [t for _, _, t in row] == ["Torsion", "Lateral", "Stable"]
            assert row[0][1] == pytest.approx(a)
    assert [bool([1 for _, _, t in row if t == "Both"]) for row in rows] == [True, True, False]


def test_links_place_every_breakpoint_before_ordering_them():
    """Two changes whose links both bend right of the straight lines (20 -> 37 -> 40 and 25 -> 42 -> 45): the
    row halfway puts each on its link (37 and 42), the first not held left of where the straight line put
    the second (35)."""
    curve = ("b", np.array([[100.0, 0.0], [100.0, 1.0e6]]))
    slices = [_Slice(1e5, [{"type": "Torsion", "V_start": 1.0, "V_end": 20.0},
                           {"type": "Both", "V_start": 20.0, "V_end": 25.0},
                           {"type": "Lateral", "V_start": 25.0, "V_end": 100.0}]),
              _Slice(3e5, [{"type": "Torsion", "V_start": 1.0, "V_end": 40.0},
                           {"type": "Both", "V_start": 40.0, "V_end": 45.0},
                           {"type": "Lateral", "V_start": 45.0, "V_end": 100.0}])]
    links = [np.array([[20.0, 1e5], [37.0, 2e5], [40.0, 3e5]]), np.array([[25.0, 1e5], [42.0, 2e5], [45.0, 3e5]])]
    rows, _ = map_shading.row_segments(slices, [curve], [2e5], (1.0, 200.0), links)
    assert rows[0][:3] == [(1.0, pytest.approx(37.0), "Torsion"), (pytest.approx(37.0), pytest.approx(42.0), "Both"),
                           (pytest.approx(42.0), 100.0, "Lateral")]


def test_a_piece_one_slice_lacks_keeps_both_of_its_links():
    """Both (40-50 m/s) on the upper slice only, the lower slice's Torsion | Lateral edge at 30 m/s: the 0.8
    change joined from 30 to 40 (through 35), the 0.2 change at 50 followed down (open) through 45 at the
    row: the row's Both piece runs from 35 to 45. (Looked up on the lower slice, where the piece is put back
    at zero width at 30 m/s, both its ends took the first link there, and the piece vanished.)"""
    curve = ("b", np.array([[100.0, 0.0], [100.0, 1.0e6]]))
    slices = [_Slice(1e5, [{"type": "Torsion", "V_start": 1.0, "V_end": 30.0},
                           {"type": "Lateral", "V_start": 30.0, "V_end": 100.0}]),
              _Slice(3e5, [{"type": "Torsion", "V_start": 1.0, "V_end": 40.0},
                           {"type": "Both", "V_start": 40.0, "V_end": 50.0},
                           {"type": "Lateral", "V_start": 50.0, "V_end": 100.0}])]
    links = [np.array([[30.0, 1e5], [35.0, 2e5], [40.0, 3e5]]), np.array([[60.0, 1e5], [45.0, 2e5], [50.0, 3e5]])]
    rows, _ = map_shading.row_segments(slices, [curve], [2e5], (1.0, 200.0), links)
    assert rows[0][:3] == [(1.0, pytest.approx(35.0), "Torsion"), (pytest.approx(35.0), pytest.approx(45.0), "Both"),
                           (pytest.approx(45.0), 100.0, "Lateral")]
