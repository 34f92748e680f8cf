"""The Stability map's disturbance margins as contour lines (pages/stability_map.py, margin_figure): the cells'
margins on the grid of the cells' centres, NaN where a cell has none, drawn as labelled iso-margin lines over
the coloured markers (which keep their hover); nothing to contour (a single cell, equal margins): no lines.
The figures are built from small margin maps made here."""

from __future__ import annotations

import math
import random

import pytest

#: A margin map of 5 x 4 cells of V 0-100 m/s, Fz 100-500 kN (centres 10, 30, ..., 90 m/s; 150, ..., 450 kN).
V_RANGE, FZ_RANGE, N_V, N_FZ = (0.0, 100.0), (100e3, 500e3), 5, 4
V_CENTRES, FZ_CENTRES = [10.0, 30.0, 50.0, 70.0, 90.0], [150e3, 250e3, 350e3, 450e3]


@pytest.fixture(scope="module")
def page():
    import app  # noqa: F401 - registers the pages
    from pages import stability_map

    return stability_map


def smooth(V, Fz):
    """A smooth margin field (rad): growing with the speed and the load, 0.08 to 0.15 over the cells below."""
    return 0.001 * V + 0.0002 * Fz / 1e3 + 0.0005 * V * Fz / 1e6


def _point(V, Fz, margin):
    return {"V": V, "Fz": Fz, "type": "Bistable", "margin": margin, "tolerance": None if margin is None else 1e-4,
            "lower": margin, "upper": None if margin is None else margin * 1.005, "confirmed": margin is not None}


def _result(points):
    return {"config": "original", "params": {}, "v_range": list(V_RANGE), "fz_range": list(FZ_RANGE),
            "grid": {"n_v": N_V, "n_fz": N_FZ}, "options": {"max_size": 0.4, "rtol": 0.005, "t_max": 80.0},
            "V": V_CENTRES, "Fz": FZ_CENTRES, "points": points}


@pytest.fixture(scope="module")
def region():
    """The multistable cells (V up to 70 m/s, Fz from 250 kN) in a shuffled order; (70, 450) not computed,
    (10, 250) with no kick reaching torsional shimmy."""
    cells = [(v, f) for v in V_CENTRES if v <= 70 for f in FZ_CENTRES if f >= 250e3 and (v, f) != (70.0, 450e3)]
    points = [_point(v, f, None if (v, f) == (10.0, 250e3) else smooth(v, f)) for v, f in cells]
    random.Random(3).shuffle(points)
    return _result(points)


def _expected(V, Fz_kn, region):
    """The margin of the cell centred at (V, Fz kN) in ``region``, NaN where it has none."""
    for p in region["points"]:
        if p["V"] == pytest.approx(V) and p["Fz"] / 1e3 == pytest.approx(Fz_kn) and p["margin"] is not None:
            return p["margin"]
    return math.nan


def _same(a, b):
    return (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, rel=1e-12)


def test_the_margins_lie_on_the_grid_of_the_cells_centres_nan_where_a_cell_has_none(page, region):
    V, Fz, z = page.margin_grid(region)
    assert V == V_CENTRES and Fz == pytest.approx([150, 250, 350, 450])
    assert len(z) == N_FZ and all(len(row) == N_V for row in z)
    for j, f in enumerate(Fz):
        for i, v in enumerate(V):
            assert _same(z[j][i], _expected(v, f, region)), (v, f, z[j][i])
    assert sum(not math.isnan(m) for row in z for m in row) == 10  # 12 cells, one not computed, one not reached


def test_the_figure_draws_labelled_contour_lines_of_the_margins_over_the_markers(page, region):
    fig = page.margin_figure(region).to_dict()
    contours = [t for t in fig["data"] if t["type"] == "contour"]
    assert [t["name"] for t in contours] == ["iso-margin halo", "iso-margin lines"]
    lines = contours[1]
    # the grid cut to the cells with margins: V 10-70 m/s, Fz 250-450 kN; each cell's margin at its centre
    assert list(lines["x"]) == [10.0, 30.0, 50.0, 70.0] and list(lines["y"]) == pytest.approx([250, 350, 450])
    for j, f in enumerate(lines["y"]):
        for i, v in enumerate(lines["x"]):
            assert _same(lines["z"][j][i], _expected(v, f, region)), (v, f)
    assert math.isnan(lines["z"][0][0]) and math.isnan(lines["z"][2][3])  # not reached; not computed
    reached = [p["margin"] for p in region["points"] if p["margin"] is not None]
    for t in contours:  # lines only, no hover of their own, no colour bar, no line across the empty cells
        c = t["contours"]
        assert c["coloring"] == "lines" and t["connectgaps"] is False and t["showscale"] is False
        assert t["hoverinfo"] == "skip" and t["zorder"] == 1  # over the markers, which keep the hover
        assert min(reached) < c["start"] < c["end"] < max(reached)
        assert 4 <= round((c["end"] - c["start"]) / c["size"]) + 1 <= 8
    assert contours[0]["line"]["width"] > lines["line"]["width"]  # a halo under the line
    assert {tuple(s[1] for s in t["colorscale"]) for t in contours} == {("rgba(255,255,255,0.9)",) * 2,
                                                                        ("#1a1a1a",) * 2}
    # the markers are still there, with their hover text, under the lines
    kicks = [t for t in fig["data"] if t.get("name") == "min yaw kick"]
    assert len(kicks) == 1 and len(kicks[0]["x"]) == 10 and "click: time history" in kicks[0]["hovertemplate"]
    assert kicks[0].get("zorder", 0) == 0 and kicks[0]["marker"]["colorbar"]["title"]["text"] == "min yaw kick (rad)"


def test_each_level_is_labelled_once_on_its_line_between_two_cells_with_margins(page, region):
    fig = page.margin_figure(region).to_dict()
    c = [t for t in fig["data"] if t.get("name") == "iso-margin lines"][0]["contours"]
    levels = [c["start"] + k * c["size"] for k in range(round((c["end"] - c["start"]) / c["size"]) + 1)]
    labels = [a for a in fig["layout"]["annotations"] if a.get("name") == "iso-margin label"]
    assert [float(a["text"]) for a in labels] == pytest.approx(levels)
    for a, level in zip(labels, levels, strict=True):
        v, f = a["x"], a["y"] * 1e3
        # on an edge between two neighbouring cells with margins, where the margin interpolated along it is the level
        row = [k for k, x in enumerate(FZ_CENTRES) if x == pytest.approx(f)]
        column = [k for k, x in enumerate(V_CENTRES) if x == pytest.approx(v)]
        if row:  # along a row: between two speeds
            i = max(k for k, x in enumerate(V_CENTRES) if x <= v)
            ends = [(V_CENTRES[i], f), (V_CENTRES[i + 1], f)]
            t = (v - V_CENTRES[i]) / (V_CENTRES[i + 1] - V_CENTRES[i])
        else:  # along a column: between two loads
            assert column, (v, f)
            j = max(k for k, x in enumerate(FZ_CENTRES) if x <= f)
            ends = [(v, FZ_CENTRES[j]), (v, FZ_CENTRES[j + 1])]
            t = (f - FZ_CENTRES[j]) / (FZ_CENTRES[j + 1] - FZ_CENTRES[j])
        a0, a1 = (_expected(x, y / 1e3, region) for x, y in ends)
        assert not math.isnan(a0) and not math.isnan(a1)
        assert a0 + t * (a1 - a0) == pytest.approx(level, rel=1e-9)
        assert a["showarrow"] is False and a["bgcolor"].startswith("rgba(255,255,255")


@pytest.mark.parametrize("case", ["one cell", "a row", "equal margins", "within their tolerances", "none reached"])
def test_nothing_to_contour_draws_no_lines_and_keeps_the_markers(page, case):
    points = {"one cell": [_point(30.0, 250e3, 0.05), _point(50.0, 250e3, None), _point(30.0, 350e3, None)],
              "a row": [_point(v, 250e3, smooth(v, 250e3)) for v in V_CENTRES],
              "equal margins": [_point(v, f, 0.0) for v in (30.0, 50.0) for f in (250e3, 350e3)],
              # 0.1 to 0.10015 rad, each +- 1e-4: the spread is the bisection's, lines would draw its noise
              "within their tolerances": [_point(v, f, 0.1 + 5e-5 * k) for k, (v, f) in
                                          enumerate((v, f) for v in (30.0, 50.0) for f in (250e3, 350e3))],
              "none reached": [_point(v, f, None) for v in (30.0, 50.0) for f in (250e3, 350e3)]}[case]
    fig = page.margin_figure(_result(points)).to_dict()
    assert not [t for t in fig["data"] if t["type"] == "contour"]
    assert not [a for a in fig["layout"].get("annotations", []) if a.get("name") == "iso-margin label"]
    reached = [p for p in points if p["margin"] is not None]
    assert len([t for t in fig["data"] if t.get("name") == "min yaw kick"][0]["x"]) == len(reached)


def test_three_cells_of_a_square_are_enough_to_contour(page):
    """The browser test's plane: 2 x 2 cells, three of them with margins (Plotly draws over their triangle)."""
    points = [_point(30.0, 250e3, 0.045), _point(50.0, 250e3, 0.095), _point(30.0, 350e3, 0.118)]
    fig = page.margin_figure(_result(points)).to_dict()
    lines = [t for t in fig["data"] if t.get("name") == "iso-margin lines"][0]
    assert list(lines["z"][0]) == [0.045, 0.095] and lines["z"][1][0] == 0.118 and math.isnan(lines["z"][1][1])
    assert (lines["contours"]["start"], lines["contours"]["end"], lines["contours"]["size"]) == (0.05, 0.11, 0.01)


@pytest.mark.parametrize(("low", "high", "levels"), [
    (0.0, 0.152, [0.025, 0.05, 0.075, 0.1, 0.125, 0.15]),
    (0.0165, 0.05, [0.02, 0.025, 0.03, 0.035, 0.04, 0.045]),
    (0.0, 0.4, [0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35]),
    (0.045, 0.118, [0.05, 0.06, 0.07, 0.08, 0.09, 0.1, 0.11]),
    (0.1, 0.1, []),
])
def test_levels_are_round_evenly_spaced_and_strictly_inside_the_margins(page, low, high, levels):
    assert page.margin_levels(low, high) == levels


def test_levels_number_4_to_8_whatever_the_spread(page):
    rng = random.Random(7)
    for _ in range(500):
        low = rng.choice([0.0, rng.uniform(0, 0.3)])
        high = low + 10 ** rng.uniform(-5, 0)
        levels = page.margin_levels(low, high)
        assert 4 <= len(levels) <= 8, (low, high, levels)
        assert low < levels[0] and levels[-1] < high
        steps = {round(b - a, 12) for a, b in zip(levels, levels[1:])}
        assert len({float(f"{s:.6g}") for s in steps}) == 1


def test_the_long_heading_is_a_title_and_a_subtitle_above_the_plot(page, region):
    """Plotly does not wrap a title: the margins' heading (cut at 1024 px when it was one line) is a short
    title and a subtitle, the reason the map is missing on a line of its own, the top margin and the
    title's pad grown by a line for each subtitle line."""
    from ui import style

    without = page.margin_figure(region, None, "").to_dict()["layout"]
    title = without["title"]
    assert title["text"] == f"{style.CONFIG_LABELS['original']}: smallest yaw kick to torsional shimmy"
    assert len(title["text"]) < 70
    lines = title["subtitle"]["text"].split("<br>")
    assert lines == [f"from straight rolling, in the {len(region['points'])} cells where it coexists with another "
                     "attractor", "(compute the map above to see its regions under them)"]
    assert all(len(line) < 90 for line in lines)
    assert without["margin"]["t"] == style.MARGIN["t"] + 2 * style.SUBTITLE_LINE
    assert title["pad"]["b"] == 12 + 2 * style.SUBTITLE_LINE
    assert without["margin"]["b"] == page.BOTTOM  # the legends' room, set after
    mapped = page.margin_figure(region, {"regions": [], "hopf_curves": [], "fold_curves": [], "torus_curves": []},
                                "").to_dict()["layout"]
    assert "<br>" not in mapped["title"]["subtitle"]["text"]
    assert mapped["margin"]["t"] == style.MARGIN["t"] + style.SUBTITLE_LINE
