"""The pages' figures speak one language (issue 30 items 4, 6, 10): every special point drawn with its
marker from ui/markers.py, whatever the page; loads in kN and l_g delta in mm on every axis; no SI
prefix on an axis ("400µ"); curves over a map's shading with a halo; log-speed axes written out.
The figures are built by the pages' own functions from small results made here."""

from __future__ import annotations

import json

import pytest

from shimmy.continuation.kinds import PointKind
from ui import markers, style

#: The symbols a page must only use for their kind (square and circle-open also mark cells and shading keys).
VOCABULARY_ONLY = {m.symbol: m.label for k, m in markers.MARKERS.items()
                   if k in (PointKind.HOPF, PointKind.GENERALISED_HOPF, PointKind.DOUBLE_HOPF,
                            PointKind.FOLD_OF_CYCLES, PointKind.PERIOD_DOUBLING)}


@pytest.fixture(scope="module")
def pages():
    import app  # noqa: F401 - registers the pages
    from pages import bifurcation, ground_run, overview, stability_map, study

    return {"bifurcation": bifurcation, "ground_run": ground_run, "overview": overview,
            "stability_map": stability_map, "study": study}


def _diagram(config="nes"):
    points = [{"V": v, "stable": v < 6 or v > 70, "period": None, "max_psi": 0.0, "max_lateral": 0.0, "mode": None}
              for v in (1.0, 6.0, 70.0, 200.0)]
    cycle = [{"V": v, "stable": v < 50, "period": 0.08, "max_psi": 0.004 * v, "max_lateral": 4e-4 * v,
              "mode": "torsional"} for v in (6.0, 30.0, 50.0, 60.0, 70.0)]
    special = [{"kind": "LPC", "V": 50.0, "max_psi": 0.2, "max_lateral": 0.02, "period": 0.08},
               {"kind": "NS", "V": 60.0, "max_psi": 0.24, "max_lateral": 0.024, "period": 0.08},
               {"kind": "PD", "V": 65.0, "max_psi": 0.26, "max_lateral": 0.026, "period": 0.08}]
    return {"config": config, "Fz": 150e3, "max_psi": 0.2, "max_psi_V": 50.0, "warnings": [],
            "hopf_points": [{"V": 6.0, "frequency_hz": 10.0, "criticality": "supercritical"},
                            {"V": 70.0, "frequency_hz": 12.0, "criticality": "supercritical"}],
            "branches": [{"kind": "equilibrium", "points": points,
                          "special_points": [{"kind": "H", "V": 6.0}, {"kind": "H", "V": 70.0}]},
                         {"kind": "periodic", "points": cycle, "special_points": special}]}


CURVE = [{"V": 10.0, "Fz": 100e3}, {"V": 50.0, "Fz": 300e3}, {"V": 90.0, "Fz": 120e3}]


def _map(config="nes"):
    return {"config": config, "V": [1.0, 200.0], "Fz": [100e3, 400e3], "types": [["Stable", "Torsion"]] * 2,
            "regions": [{"type": "Torsion", "V": [10.0, 50.0, 90.0, 10.0], "Fz": [100e3, 300e3, 120e3, 100e3]}],
            "hopf_curves": [CURVE], "fold_curves": [CURVE], "torus_curves": [CURVE],
            "gh_points": [{"V": 50.0, "Fz": 300e3}], "double_hopf_points": [{"V": 90.0, "Fz": 120e3}]}


def _hopf_curves(config):
    return {"config": config, "curves": [{"points": [{**p, "frequency_hz": 10.0, "lyapunov": None} for p in CURVE]}],
            "gh_points": [{"V": 50.0, "Fz": 300e3}], "double_hopf_points": [{"V": 90.0, "Fz": 120e3}]}


def _study():
    rows = [{"e_p": p, "config": "nes", "hopf_start": 6.0, "hopf_end": 70.0, "max_psi": 0.1 + p * 10,
             "max_psi_V": 40.0, "warnings": []} for p in (0.001, 0.002, 0.003)]
    curves = [{"config": "nes", "quantity": "hopf_V_start", "p": [0.001, 0.002, 0.003], "values": [6.0, 6.5, 7.0],
               "special_points": [{"kind": "HH", "p": 0.002, "value": 6.5, "located": True},
                                  {"kind": "P2_TURN", "p": 0.003, "value": 7.0, "located": True}]}]
    return {"parameters": ["e_p"], "configs": ["nes"], "Fz": 150e3, "rows": rows, "curves": curves}


def _ground_run(config="nes"):
    rows = [[0.0, 10.0, 150e3], [10.0, 40.0, 120e3], [20.0, 70.0, 60e3]]
    n = 3
    return {"config": config, "profile": {"name": "takeoff", "rows": rows},
            "hopf_curves": [{"V": [p["V"] for p in CURVE], "Fz": [p["Fz"] for p in CURVE]}],
            "options": {"psi_threshold": 0.01, "lateral_threshold": 0.001},
            "t": [0.0, 10.0, 20.0], "V": [10.0, 40.0, 70.0], "Fz": [150e3, 120e3, 60e3],
            "psi": [0.0] * n, "lateral": [0.0] * n, "envelope_psi": [0.001, 0.05, 0.02],
            "envelope_lateral": [1e-5, 4e-4, 2e-4],
            "boundary_crossings": [{"t": 5.0, "V": 25.0, "Fz": 130e3}]}


@pytest.fixture(scope="module")
def figures(pages):
    """Every figure of the pages that draws special points, loads or l_g delta, as Plotly dicts."""
    from ui import compare

    series = compare.series(["A", "B"])
    stability = {"Fz": 150e3, "V": [1.0, 200.0], "configs": {
        c: {"unstable_intervals": [[6.0, 70.0]], "hopf_points": [{"V": 6.0}, {"V": 70.0}]}
        for c in pages["overview"].CONFIGS}}
    gr = [_ground_run(c) for c in pages["ground_run"].CONFIGS]
    return {
        "bifurcation": pages["bifurcation"].figure([_diagram("nes"), _diagram("pd")]).to_dict(),
        "bifurcation designs": pages["bifurcation"].figure([_diagram(), _diagram()], series, what="design").to_dict(),
        # as the browser gets them: plotly's JSON (the map's hover grid is sent as arrays, a typed one of codes)
        "stability map": json.loads(pages["stability_map"].figure([_map("original"), _map("nes")]).to_json()),
        "stability map designs": json.loads(pages["stability_map"].figure([_map(), _map()], series,
                                                                          what="design").to_json()),
        "overview boundary": pages["overview"].boundary_figure([_hopf_curves("original"),
                                                                _hopf_curves("nes")]).to_dict(),
        "overview intervals": pages["overview"].intervals_figure([stability, stability], ["A", "B"]).to_dict(),
        "study": pages["study"].figure(_study()).to_dict(),
        "ground run plane": pages["ground_run"].plane(gr[1]).to_dict(),
        "ground run envelopes": pages["ground_run"].envelopes(gr, "t").to_dict(),
    }


def _marked(fig):
    """(kind, symbol) of every trace that draws a special point or its legend entry."""
    return [(t["meta"]["kind"], t["marker"]["symbol"]) for t in fig["data"]
            if isinstance(t.get("meta"), dict) and "kind" in t["meta"]]


def test_every_page_draws_each_kind_of_point_with_its_one_marker(figures):
    expected = {m.label: m.symbol for m in markers.MARKERS.values()}
    drawn = {}
    for name, fig in figures.items():
        for kind, symbol in _marked(fig):
            assert symbol == expected[kind], (name, kind, symbol)
            drawn.setdefault(kind, set()).add(name.split()[0])
        for t in fig["data"]:  # no vocabulary symbol drawn for anything but its kind
            symbol = (t.get("marker") or {}).get("symbol")
            if symbol in VOCABULARY_ONLY:
                assert (t.get("meta") or {}).get("kind") == VOCABULARY_ONLY[symbol], (name, t.get("name"), symbol)
    # the kinds of the issue, each on the pages that have it: one diamond for H, one star for GH everywhere
    assert {"bifurcation", "overview", "ground"} <= drawn["H"]
    assert {"stability", "overview"} <= drawn["GH"]
    assert {"stability", "overview", "study"} <= drawn["HH"]
    assert {"bifurcation"} <= drawn["LPC"] and {"bifurcation"} <= drawn["NS"] and {"bifurcation"} <= drawn["PD"]
    assert markers.of("GH").symbol == "star" and markers.of("HH").symbol == "hexagram"
    assert markers.of("H").symbol == "diamond" and markers.of("LPC").symbol == "triangle-up"
    assert markers.of("NS").symbol == "square" and markers.of("PD").symbol == "x"


def test_legends_name_the_kinds_with_the_same_markers(figures):
    keys = {t["name"]: t["marker"]["symbol"] for fig in figures.values() for t in fig["data"]
            if t.get("x") == [None] and isinstance(t.get("meta"), dict) and "kind" in t["meta"]}
    assert keys["H: Hopf"] == "diamond" and keys["GH: generalised Hopf"] == "star"
    assert keys["HH: double Hopf"] == "hexagram" and keys["LPC: fold of cycles"] == "triangle-up"


def test_loads_read_in_kn_and_lateral_displacements_in_mm_without_si_prefixes(figures):
    for name, fig in figures.items():
        text = json.dumps(fig)
        assert "µ" not in text, name
        template_axes = fig["layout"]["template"]["layout"]
        assert template_axes["xaxis"]["exponentformat"] == template_axes["yaxis"]["exponentformat"] == "none", name
        for key, axis in fig["layout"].items():
            if key.startswith(("xaxis", "yaxis")):
                assert axis.get("exponentformat", "none") == "none", (name, key)
                title = (axis.get("title") or {}).get("text") or ""
                assert "(N)" not in title, (name, key, title)
                if "Fz" in title:
                    assert title.endswith("(kN)"), (name, key, title)
                if "l_g delta" in title:
                    assert title.endswith("(mm)"), (name, key, title)
    assert figures["bifurcation"]["layout"]["yaxis2"]["title"]["text"] == "max |l_g delta| (mm)"
    lateral = [t for t in figures["bifurcation"]["data"] if t.get("yaxis") == "y2" and t.get("mode") == "lines"]
    assert max(max(t["y"]) for t in lateral) == pytest.approx(0.028 * 1e3)  # 0.028 m drawn as 28 mm
    plane = figures["ground run plane"]
    assert plane["layout"]["yaxis"]["title"]["text"] == "nose-gear load Fz (kN)"
    assert [t for t in plane["data"] if t.get("name") == "trajectory"][0]["y"] == [150.0, 120.0, 60.0]


def test_angles_carry_degrees_in_their_hover_text(figures):
    psi = [t for t in figures["bifurcation"]["data"] if t.get("yaxis") in (None, "y") and t.get("mode") == "lines"
           and t["x"] != [None]]
    assert psi and all("°" in t["hovertemplate"] and t["customdata"] for t in psi)
    largest = [t for t in figures["bifurcation"]["data"] if (t.get("meta") or {}).get("mark") == "largest stable |psi|"]
    assert [(t["x"], t["y"]) for t in largest] == [([50.0], [0.2])] * 2
    assert largest[0]["customdata"][0] == pytest.approx(11.459, abs=1e-3)  # 0.2 rad in degrees


def test_map_curves_read_over_every_region_colour(figures):
    assert style.SHIMMY_TYPE_COLOURS["Torsion"] != style.CONFIG_COLOURS["nes"]
    assert style.SHIMMY_TYPE_COLOURS["Torsion"] == "#F0E442"
    for name in ("stability map", "stability map designs"):
        data = figures[name]["data"]
        curves = [k for k, t in enumerate(data) if str(t.get("name", "")).endswith((": Hopf", ": fold of cycles",
                                                                                     ": torus"))]
        assert len(curves) == 6
        for k in curves:  # each curve right over its halo: a wider, white line with the same points
            halo = data[k - 1]
            assert halo["meta"]["halo"] and halo["x"] == data[k]["x"]
            assert halo["line"]["width"] > data[k]["line"]["width"] and halo["line"]["color"].startswith("rgba(255")


def test_log_speed_axes_write_20_and_200_out(figures):
    for name in ("overview boundary", "overview intervals"):
        axis = figures[name]["layout"]["xaxis"]
        assert axis["type"] == "log" and {20, 200} <= set(axis["tickvals"]), name
        assert dict(zip(axis["tickvals"], axis["ticktext"], strict=True))[20] == "20"
    lay = style.layout("growth", "forward speed V (m/s)", "rate", x_log=True)
    assert lay["xaxis"]["tickformat"] == "~g" and 200 in lay["xaxis"]["tickvals"]


def test_a_placeholder_wraps_instead_of_running_off_a_narrow_figure():
    text = style.message_figure("Press Compute: tens of seconds per configuration cold on 2 cores, instant "
                                "from the cache; then it follows the design where a nearby design is cached")
    lines = text.layout.annotations[0].text.split("<br>")
    assert len(lines) >= 2 and max(len(line) for line in lines) <= style.MESSAGE_WIDTH


def test_the_study_marks_its_largest_stable_amplitude_and_says_which_parameter_the_design_line_follows(figures):
    fig = figures["study"]
    largest = [t for t in fig["data"] if (t.get("meta") or {}).get("mark") == "largest stable |psi|"]
    assert [(t["x"], t["y"]) for t in largest] == [([0.003], [pytest.approx(0.13)])]
    assert fig["layout"]["meta"]["study"] == {"parameter": "e_p", "unit": "m"}  # the browser draws the line there
    assert "current design" in [t["name"] for t in fig["data"] if t.get("x") == [None]]


def test_downloads_write_loads_in_kn_and_lateral_displacements_in_mm(pages):
    gr = [_ground_run(c) for c in pages["ground_run"].CONFIGS]
    columns, rows = pages["ground_run"]._csv_rows(gr)
    assert columns == ["config", "t_s", "V_m_s", "Fz_kN", "psi_rad", "lateral_mm", "envelope_psi_rad",
                       "envelope_lateral_mm"]
    assert rows[1][3] == pytest.approx(120.0) and rows[1][7] == pytest.approx(0.4)
    columns, rows = pages["bifurcation"]._csv_rows([_diagram()])
    assert "max_lateral_mm" in columns and rows[-1][columns.index("max_lateral_mm")] == pytest.approx(28.0)
    columns, _ = pages["stability_map"]._csv_rows([_map()])
    assert columns[1] == "Fz_kN"


def test_stacked_legends_leave_a_wrapped_row_its_room(figures):
    """The legends under a figure stack down from its plot; the map's "curves, points" row wraps onto a
    second line at 1024 px (six entries), so the shading row starts that much lower (it overlapped the
    wrapped "HH: double Hopf" entry), and every legend stays inside the bottom margin."""
    for name in ("stability map", "stability map designs", "bifurcation", "study"):
        layout = figures[name]["layout"]
        keys = sorted((k for k in layout if k.startswith("legend")), key=lambda k: int(k[6:] or 1))
        height, bottom = layout["height"], layout["margin"]["b"]
        tops = [layout[k]["y"] * height for k in keys]  # px above the figure's bottom edge
        assert tops[0] < bottom - 40 and tops[-1] > 20, (name, tops, bottom)
        gaps = [a - b for a, b in zip(tops, tops[1:])]
        assert all(g >= style.LEGEND_ROW - 1e-9 for g in gaps), (name, gaps)
    layout = figures["stability map"]["layout"]
    assert (layout["legend2"]["y"] - layout["legend3"]["y"]) * layout["height"] >= 1.4 * style.LEGEND_ROW


def test_long_design_names_give_their_legend_row_the_lines_they_take(pages):
    """Up to four design names of up to 80 characters wrap the first legend row at 1024 px: the rows
    below start under its last line, and the figure grows by those lines (the plot keeps its height)."""
    from ui import compare

    names = ["A design named at length to say what changed in it"] * 1 + ["B " + "x" * 60, "C short", "D " + "y" * 40]
    series = compare.series(names)
    lines = style.legend_lines("design (colour)", [label for label, _ in series])
    assert lines >= 3
    for name, fig, short in (
            ("map", pages["stability_map"].figure([_map()] * 4, series, what="design").to_dict(),
             pages["stability_map"].figure([_map(), _map()], compare.series(["A", "B"]), what="design").to_dict()),
            ("bifurcation", pages["bifurcation"].figure([_diagram()] * 4, series, what="design").to_dict(),
             pages["bifurcation"].figure([_diagram()] * 2, compare.series(["A", "B"]), what="design").to_dict())):
        layout, base = fig["layout"], short["layout"]
        extra = int(style.LEGEND_ROW * (lines - 1))
        assert layout["height"] == base["height"] + extra and layout["margin"]["b"] == base["margin"]["b"] + extra
        tops = [layout[k]["y"] * layout["height"] for k in ("legend", "legend2", "legend3")]
        assert tops[0] - tops[1] >= lines * style.LEGEND_ROW - 1e-9, name
        assert tops[0] == pytest.approx(base["legend"]["y"] * base["height"] + extra), name  # as far under the plot
        assert tops[2] > 20, name
    assert style.legend_lines("configuration (colour)", ["Original", "NES", "PD", "NES+PD"]) == 1
