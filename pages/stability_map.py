"""(V, Fz) stability maps: the plane shaded by shimmy type, with Hopf, fold and torus curves."""

from __future__ import annotations

import itertools
import math
from urllib.parse import urlencode

import dash
import numpy as np
from dash import Input, Output, State, dcc, html, no_update

from shimmy.continuation.kinds import PointKind
from shimmy.errors import InvalidParameterError
import shimmy.model.units as units
from shimmy.service import analyses, neighbours
from ui import compare, designs, fields, formats, ids, jobs, live, markers, merits
from ui import components as ui
from ui import style
from ui.fields import Quantity
from ui.layout import page

dash.register_page(__name__, path="/stability-map", name="Stability map", order=4)

CONFIGS = ui.CONFIGS
TYPES = tuple(style.SHIMMY_TYPE_COLOURS)
CURVE_STYLES = {"hopf_curves": ("Hopf", "solid", 2.6), "fold_curves": ("fold of cycles", "dash", 2.2),
                "torus_curves": ("torus", "dot", 2.2)}


FZ_MIN = Quantity("map", "fz_min", "Fz from", "kN", 1e3)
FZ_MAX = Quantity("map", "fz_max", "Fz to", "kN", 1e3)
V_MIN = Quantity("map", "v_min", "V from", "m/s")
V_MAX = Quantity("map", "v_max", "V to", "m/s")
SLICES = Quantity("map", "resolution", "Fz slices", "")
METRICS_FZ = Quantity("map", "metrics_Fz", "figures at Fz", "kN", 1e3)
CELLS_V = Quantity("margin_map", "n_v", "cells in V", "")
CELLS_FZ = Quantity("margin_map", "n_fz", "cells in Fz", "")
MAX_KICK = Quantity("margin_map", "max_size", "largest kick", "rad")
WAITING = "Press Compute: tens of seconds per configuration cold on 2 cores, instant from the cache"
MARGIN_WAITING = ("Press Compute margins: the smallest yaw kick to torsional shimmy in each cell of the plane where "
                  "it coexists with another attractor (20 to 40 s for 20 x 10 cells on 2 cores)")
HEIGHT, BOTTOM = 750, 190
FAINT, FAINT_REGIONS = 0.35, 0.16  # a previous design's curves and regions under the map being made
MARGIN_REGIONS = 0.4  # the map's regions under the margins
#: The iso-margin lines and their labels (rad): dark, the lines over a white halo and the labels on white, to read
#: on the Viridis markers and on every region's colour.
MARGIN_LINES = {"color": "#1a1a1a", "width": 1.3}
MARGIN_STEPS = (5.0, 2.5, 2.0, 1.0)  # the step between two iso-margin lines: one of these x 10^k rad
MARGIN_LEVELS = 4  # at least so many iso-margin lines (the largest step giving as many: 4 to 8)
PLOT_PX = (490, 480)  # the plot's width and height (px) in a 1024 px window: where the lines' labels must not overlap
LABEL_PX = (6.5, 16)  # a label's width per character and its height (px)


def layout(shade: str | None = None, overlay: str | None = None, fz_min: str | None = None,
           fz_max: str | None = None, v_min: str | None = None, v_max: str | None = None,
           resolution: str | None = None, compare_config: str | None = None, compare_fz: str | None = None,
           margin_nv: str | None = None, margin_nfz: str | None = None, margin_max: str | None = None, **query):
    shade, bad_shade = fields.choice("shade", shade, list(CONFIGS), "original", "a configuration")
    compared, bad_compared = fields.choice("compare_config", compare_config, CONFIGS, "nes_pd", "a configuration")
    merit_fz, bad_merit_fz = METRICS_FZ.from_url("compare_fz", compare_fz, 150)
    others, bad_overlay = fields.choices_list("overlay", overlay, CONFIGS, [], "a configuration")
    others = [c for c in others if c != shade]
    values, problems = {}, [bad_shade, bad_overlay]
    for key, q, raw, default in (("fz_min", FZ_MIN, fz_min, 10), ("fz_max", FZ_MAX, fz_max, 900),
                                 ("v_min", V_MIN, v_min, 1), ("v_max", V_MAX, v_max, 200),
                                 ("resolution", SLICES, resolution, SLICES.spec.default)):
        values[key], problem = q.from_url(key, raw, default)
        problems.append(problem)
    cells = {}
    for key, q, raw in (("margin_nv", CELLS_V, margin_nv), ("margin_nfz", CELLS_FZ, margin_nfz),
                        ("margin_max", MAX_KICK, margin_max)):
        cells[key], problem = q.from_url(key, raw, q.spec.default)
        problems.append(problem)
    return page(
        query, ids.MAP,
        ui.header("Stability map", "The (V, Fz) plane shaded by shimmy type, from the stable attractors on each load "
                  "slice (equilibrium, torsional and lateral limit cycles, including those reached from large "
                  "torsional and lateral starts; simulation where none is stable). Hopf, fold-of-cycles and torus "
                  "curves, GH and double-Hopf points by two-parameter continuation; the operating points A-I "
                  "marked. Click a point to open its time history."),
        html.Div([
            ui.field("Shade by", ui.configurations(ids.MAP_SHADE, shade)),
            ui.field("Overlay curves of", ui.configurations(ids.MAP_OVERLAY, others, multi=True)),
            html.Div([FZ_MIN.field("Fz from (kN)", ids.MAP_FZMIN, values["fz_min"]),
                      FZ_MAX.field("to (kN)", ids.MAP_FZMAX, values["fz_max"])], className="pair"),
            html.Div([V_MIN.field("V from (m/s)", ids.MAP_VMIN, values["v_min"]),
                      V_MAX.field("to (m/s)", ids.MAP_VMAX, values["v_max"])], className="pair"),
            SLICES.field(f"Fz slices ({SLICES.low:g}-{SLICES.high:g})", ids.MAP_RES, values["resolution"]),
            *jobs.controls(ids.MAP_GROUP),
        ], className="controls"),
        html.Div(" ".join(p for p in problems if p), id=ids.MAP_GROUP.error, className="error", role="alert"),
        ui.graph(ids.MAP_GRAPH, figure=style.message_figure(WAITING, 600)),
        html.Div(id=ids.MAP_HINT, className="hint"),
        html.Div(id=ids.MAP_TABLE, className="table-wrap"),
        ui.downloads(ids.MAP_GROUP),
        *jobs.stores(ids.MAP_GROUP),
        live.settled(ids.MAP),
        dcc.Location(id=ids.MAP_NAV, refresh="callback-nav"),
        html.H2("Disturbance margins"),
        html.P("Where two attractors coexist, which one the gear ends on depends on the kick. In each cell of the "
               "plane above where a torsional limit cycle (the fatigue-critical shimmy) coexists with another "
               "attractor (the Bistable cells, and any where straight rolling is stable beside a cycle): the "
               "smallest yaw kick from straight rolling that ends on the torsional cycle, for the shaded "
               "configuration and this design, each checked by two runs. 0: the standard start (psi = 0.001 rad) "
               "already ends there. Each cell is a coloured square (its margin on hover) under labelled contour "
               "lines of equal kick (rad); click a cell to run its time history from just above its kick.",
               className="hint"),
        html.Div([CELLS_V.field(f"Cells in V ({CELLS_V.low:g}-{CELLS_V.high:g})", ids.MAPM_NV, cells["margin_nv"]),
                  CELLS_FZ.field(f"Cells in Fz ({CELLS_FZ.low:g}-{CELLS_FZ.high:g})", ids.MAPM_NFZ,
                                 cells["margin_nfz"]),
                  MAX_KICK.field("Largest kick (rad)", ids.MAPM_MAX, cells["margin_max"]),
                  *jobs.controls(ids.MAPM, "Compute margins")], className="controls"),
        html.Div(id=ids.MAPM.error, className="error", role="alert"),
        ui.graph(ids.MAPM_GRAPH, figure=style.message_figure(MARGIN_WAITING, 360)),
        html.Div(id=ids.MAPM_HINT, className="hint"),
        html.Div(id=ids.MAPM_TABLE, className="table-wrap"),
        ui.downloads(ids.MAPM),
        *jobs.stores(ids.MAPM),
        dcc.Location(id=ids.MAPM_NAV, refresh="callback-nav"),
        html.H2("Compare saved designs"),
        html.P("The designs ticked under Compare in the design panel (2 to 4; the current one may be one of them) "
               "over this page's Fz and V ranges and slices, for one configuration: the Hopf, fold and torus curves "
               "of each design in its colour, the shading of the first; their figures of merit below, each with "
               "its change against the first.", className="hint"),
        html.Div([ui.field("Configuration", ui.configurations(ids.MAPC_CONFIG, compared)),
                  METRICS_FZ.field("Figures at Fz (kN)", ids.MAPC_FZ, merit_fz),
                  *jobs.controls(ids.MAPC, "Compare")], className="controls"),
        html.Div(id=ids.MAPC.designs, className="compare-designs"),
        compare.follower(ids.MAP),
        html.Div(" ".join(p for p in (bad_compared, bad_merit_fz) if p), id=ids.MAPC.error, className="error",
                 role="alert"),
        ui.graph(ids.MAPC_GRAPH, figure=style.message_figure(compare.waiting_text(
            "tens of seconds per design cold on 2 cores, instant from the cache"), 360)),
        html.Div(id=ids.MAPC_TABLE, className="table-wrap"),  # its heading comes with the table
        ui.downloads(ids.MAPC),
        *jobs.stores(ids.MAPC),
    )


for _box, _quantity in ((ids.MAP_FZMIN, FZ_MIN), (ids.MAP_FZMAX, FZ_MAX), (ids.MAP_VMIN, V_MIN),
                        (ids.MAP_VMAX, V_MAX), (ids.MAP_RES, SLICES), (ids.MAPM_NV, CELLS_V), (ids.MAPM_NFZ, CELLS_FZ),
                        (ids.MAPM_MAX, MAX_KICK), (ids.MAPC_FZ, METRICS_FZ)):
    fields.check(_box, _quantity)


def _requests(shade, overlay, fz_min, fz_max, v_min, v_max, resolution, design):
    configs = [shade] + [c for c in overlay or [] if c != shade]
    lo, hi = FZ_MIN.read(fz_min), FZ_MAX.read(fz_max)
    if not hi > lo:
        raise InvalidParameterError("fz_max", fz_max, f"above {fz_min:g} kN",
                                    message=f"Fz to = {fz_max:g} kN must exceed Fz from = {fz_min:g} kN")
    v_lo, v_hi = V_MIN.read(v_min), V_MAX.read(v_max)
    if not v_hi > v_lo:
        raise InvalidParameterError("v_max", v_max, f"above {v_min:g} m/s",
                                    message=f"V to = {v_max:g} m/s must exceed V from = {v_min:g} m/s")
    slices = SLICES.read(resolution)
    return [{"config": c, "fz_min": lo, "fz_max": hi, "v_min": v_lo, "v_max": v_hi, "resolution": slices, **design}
            for c in configs]


CONTROLS = (State(ids.MAP_SHADE, "value"), State(ids.MAP_OVERLAY, "value"), State(ids.MAP_FZMIN, "value"),
            State(ids.MAP_FZMAX, "value"), State(ids.MAP_VMIN, "value"), State(ids.MAP_VMAX, "value"),
            State(ids.MAP_RES, "value"), State(ids.design_store(ids.MAP), "data"))
STALE = ("The design changed: the map shown is of the previous design. Press Compute for this one (no map of a "
         "nearby design is cached to start from).")


def _csv_rows(results):
    rows = [[r["config"], units.to_kn(Fz), V, t] for r in results for Fz, row in zip(r["Fz"], r["types"], strict=True)
            for V, t in zip(r["V"], row, strict=True)]
    return ["config", "Fz_kN", "V_m_s", "shimmy_type"], rows


def _warm(requests: list[dict]) -> bool:
    """Whether every map asked for can start from the cached map of a nearby design (a quick look
    at the cache's list of designs, nothing computed)."""
    return all(neighbours.within_reach("map", r) for r in requests)


def _fading(seconds: float, asked: str) -> tuple:
    """While a map warmed from a nearby design is made: the previous map, faint."""
    return live.fading("New design's map", seconds), no_update


def _sketch(sketches, previous, live) -> tuple:
    """While maps are made: their curves so far (:func:`sketch_figure`)."""
    return sketch_figure(sketches, previous, live), no_update


def _computing(seconds: float, asked: str) -> tuple:
    """The figure while the map is made: what is computed and for how long so far (the step under
    way and the progress are in the line above it)."""
    so_far = f"{seconds:.0f} s" if seconds < 60 else f"{int(seconds) // 60} min {int(seconds) % 60:02d} s"
    return style.message_figure(f"Computing the map ({asked}): {so_far} so far…", 600), None


jobs.register(
    ids.MAP_GROUP, "map", requests=lambda _settled, *controls: _requests(*controls),
    render=lambda results: (figure(results), summary(results)),
    clock=_computing, waiting=lambda: (style.message_figure(WAITING, 600), None),
    follow=[live.follow_settled(ids.MAP)], warm=_warm, fading=_fading, stale=STALE, sketch=_sketch,
    outputs=[Output(ids.MAP_GRAPH, "figure"), Output(ids.MAP_TABLE, "children")], states=CONTROLS,
    lock=[ids.MAP_SHADE, ids.MAP_RES, ids.MAP_FZMIN, ids.MAP_FZMAX, ids.MAP_VMIN, ids.MAP_VMAX],
    download=jobs.Download(ids.MAP_GROUP, "stability_map", _csv_rows),
    blank=lambda: (style.message_figure("Refused: see the message above", 600), None))


def _margin_requests(shade, fz_min, fz_max, v_min, v_max, resolution, design, n_v, n_fz, max_size):
    """The margins of the shaded configuration over the page's plane, for the current design."""
    plane = _requests(shade, [], fz_min, fz_max, v_min, v_max, resolution, design)[0]
    plane.pop("resolution")
    return [{**plane, "n_v": CELLS_V.read(n_v), "n_fz": CELLS_FZ.read(n_fz), "max_size": MAX_KICK.read(max_size)}]


def _margin_csv(results):
    r = results[0]
    rows = [[r["config"], p["V"], units.to_kn(p["Fz"]), p["type"], "+".join(a["mode"] for a in p["attractors"]),
             p["margin"],
             p["tolerance"], p["lower"], p["upper"], p["confirmed"], p["note"]] for p in r["points"]]
    return ["config", "V_m_s", "Fz_kN", "shimmy_type", "attractors", "min_yaw_kick_rad", "tolerance_rad",
            "lower_rad", "upper_rad", "confirmed", "note"], rows


MARGINS_STALE = ("Press Compute margins for this configuration and design (any margins shown are of the previous "
                 "ones).")
jobs.register(
    ids.MAPM, "margin_map", requests=lambda _shade, _design, *states: _margin_requests(*states),
    render=lambda results: (margin_table(results[0]),), stale=MARGINS_STALE,
    follow=[Input(ids.MAP_SHADE, "value"), Input(live.settled_id(ids.MAP), "data")],
    outputs=[Output(ids.MAPM_TABLE, "children")],
    states=[State(ids.MAP_SHADE, "value"), State(ids.MAP_FZMIN, "value"), State(ids.MAP_FZMAX, "value"),
            State(ids.MAP_VMIN, "value"), State(ids.MAP_VMAX, "value"), State(ids.MAP_RES, "value"),
            State(ids.design_store(ids.MAP), "data"), State(ids.MAPM_NV, "value"), State(ids.MAPM_NFZ, "value"),
            State(ids.MAPM_MAX, "value")],
    lock=[ids.MAPM_NV, ids.MAPM_NFZ, ids.MAPM_MAX],
    download=jobs.Download(ids.MAPM, "disturbance_margins", _margin_csv, single=True,
                           filename=lambda results: f"disturbance_margins_{results[0]['config']}"),
    blank=lambda: (None,))


def _compare_requests(fz_min, fz_max, v_min, v_max, resolution, config, merit_fz, selection, saved, current):
    """The page's map request for one configuration, once per compared design (the figures of merit at
    the load asked; at 150 kN it is the request of the page's own map: the cache serves it)."""
    common = _requests(config, [], fz_min, fz_max, v_min, v_max, resolution, {})[0]
    common["metrics_Fz"] = METRICS_FZ.read(merit_fz)
    return [{**common, **d.request()} for d in compare.chosen(selection, saved, current)]


def _compare_names(*values):
    return [d.name for d in compare.chosen(*values[7:])]


def _merits(results, names):
    fz = results[0]["metrics"]["at_Fz"]["Fz"]
    return designs.comparison(names, [r["metrics"] for r in results], designs.merit_figures(fz))


def _compare_render(results, names):
    series = compare.series(names)
    return figure(results, series, what="design"), [html.H3("Figures of merit"),
                                                     compare.table(_merits(results, names), ids.MAPC_SUMMARY)]


jobs.register(
    ids.MAPC, "map", requests=_compare_requests, labels=_compare_names, render=_compare_render,
    outputs=[Output(ids.MAPC_GRAPH, "figure"), Output(ids.MAPC_TABLE, "children")],
    states=[State(ids.MAP_FZMIN, "value"), State(ids.MAP_FZMAX, "value"), State(ids.MAP_VMIN, "value"),
            State(ids.MAP_VMAX, "value"), State(ids.MAP_RES, "value"), State(ids.MAPC_CONFIG, "value"),
            State(ids.MAPC_FZ, "value"), State(ids.DESIGN_COMPARE, "value"), State(ids.SAVED, "data"),
            State(ids.design_store(ids.MAP), "data")],
    lock=[ids.MAPC_CONFIG, ids.MAPC_FZ],
    download=jobs.Download(ids.MAPC, "figures_of_merit", lambda results, names: designs.comparison_csv(
        _merits(results, names))),
    blank=lambda: (style.message_figure("Refused: see the message above", 360), None))
compare.register_selection(ids.MAPC, ids.MAP)


#: The points of a map's curves (their markers: ui/markers.py).
POINTS = {"gh_points": PointKind.GENERALISED_HOPF, "double_hopf_points": PointKind.DOUBLE_HOPF}


def figure(results, series=None, what="configuration"):
    """The first map shaded by type; the curves of every map in its configuration's colour (or
    ``series`` [(name, colour)], one per map: compared designs), each over a white halo to read on
    every region's colour; the operating points A-I. Three legends: configuration or design
    (colour), curve and point kind (line style, marker), shimmy type (shading)."""
    if series is None:
        series = [(style.CONFIG_LABELS[r["config"]], style.CONFIG_COLOURS[r["config"]]) for r in results]
    shaded = results[0]
    grid = shaded.get("shading") or shaded  # read off the curves; a map without it: its slices
    V, Fz = grid["V"], [f / units.KN for f in grid["Fz"]]
    codes = [[TYPES.index(t) for t in row] for row in grid["types"]]
    n = len(TYPES)
    scale = []
    for k, t in enumerate(TYPES):  # a stepped scale: code k -> its type's colour
        scale += [[k / n, style.SHIMMY_TYPE_COLOURS[t]], [(k + 1) / n, style.SHIMMY_TYPE_COLOURS[t]]]
    label = style.CONFIG_LABELS[shaded["config"]]
    fig = style.figure("", "forward speed V (m/s)", "vertical load Fz (kN)", height=HEIGHT)
    if what == "configuration":
        style.titled(fig, f"Shimmy type of {label} (shaded)")
    else:  # a design's name is the user's (up to 80 characters): under the title, where it has the width
        style.titled(fig, f"{label}: curves of {len(results)} designs", f"shimmy type of {series[0][0]} (shaded)")
    regions = shaded.get("regions") or []
    # the regions as polygons (their edges on the curves at every row); the grid stays underneath,
    # transparent, for the hover text and the click that opens a time history
    # as arrays, which plotly takes whole (as lists it checks every one of the 18 000 cells: 0.06-0.09 s of
    # the figure's 0.11 s; sent as a typed array, the codes' JSON is smaller too)
    fig.add_heatmap(x=np.asarray(V, float), y=np.asarray(Fz, float), z=np.asarray(codes, np.int8), zmin=0, zmax=n,
                    colorscale=scale, showscale=False, opacity=0.0 if regions else 0.6,
                    customdata=np.asarray(grid["types"], dtype=object), name="shimmy type", showlegend=False,
                    hovertemplate="V %{x:.4g} m/s<br>Fz %{y:.4g} kN<br>%{customdata}<extra>click: time history</extra>")
    _regions(fig, shaded, 0.6)
    _curves(fig, results, series, what)
    inside = [(name, v, f) for name, (v, f) in ui.OPERATING_POINTS.items()
              if min(V) <= v <= max(V) and min(Fz) <= f <= max(Fz)]
    _finish(fig, series, what, inside, (min(V), max(V)), (min(Fz), max(Fz)))
    return fig


def _curves(fig, results, series, what, faint=False):
    """Each result's Hopf, fold and torus curves and GH / double-Hopf points in its series' colour
    (``faint``: thin and pale, a previous design's under the one being made)."""
    for k, (result, (label, colour)) in enumerate(zip(results, series, strict=True)):
        group = f"{what}-{k}"
        for key, (kind, dash_style, width) in CURVE_STYLES.items():
            for curve in result[key]:
                x, y = [p["V"] for p in curve], [p["Fz"] / units.KN for p in curve]
                if not faint:  # a halo: the curve reads on every region's colour
                    fig.add_scatter(x=x, y=y, mode="lines", legendgroup=group, showlegend=False, hoverinfo="skip",
                                    line=style.halo(width), meta={"halo": kind})
                fig.add_scatter(x=x, y=y, mode="lines",
                                name=f"{label}: {kind}", legendgroup=group, showlegend=False,
                                line={"color": colour, "dash": dash_style, "width": 1.2 if faint else width},
                                opacity=FAINT if faint else 1.0,
                                hovertemplate=f"{label} {kind}<br>V %{{x:.4g}} m/s<br>Fz %{{y:.4g}} kN<extra></extra>")
        for key, kind in POINTS.items():
            points = result.get(key) or []
            if points and not faint:
                m = markers.of(kind)
                fig.add_scatter(x=[g["V"] for g in points], y=[units.to_kn(g["Fz"]) for g in points], mode="markers",
                                name=f"{label}: {m.name}", legendgroup=group, showlegend=False,
                                marker=markers.marker(kind, colour, outline="#fff"), meta={"kind": m.label},
                                hovertemplate=f"{label} {m.legend}<br>V %{{x:.4g}} m/s<br>Fz %{{y:.4g}} kN"
                                              "<extra></extra>")


def _finish(fig, series, what, inside, v_range, fz_range):
    """The operating points ``inside`` the plane, the three legends, the axes' ranges."""
    if inside:
        fig.add_scatter(x=[v for _, v, _ in inside], y=[f for _, _, f in inside], mode="markers+text",
                        text=[name for name, _, _ in inside], textposition="top right",
                        textfont={"size": 13, "color": "#111"}, name="points A-I", legend="legend2",
                        marker={"symbol": "circle", "size": 9, "color": "#fff", "line": {"width": 2, "color": "#111"}},
                        hovertemplate="operating point %{text}<br>V %{x:.4g} m/s<br>Fz %{y:.4g} kN<extra></extra>")
    for k, (label, colour) in enumerate(series):
        style.legend_key(fig, label, "legend", group=f"{what}-{k}", mode="lines", line={"color": colour, "width": 3})
    for kind, dash_style, width in CURVE_STYLES.values():
        style.legend_key(fig, kind, "legend2", mode="lines",
                         line={"color": "#444", "dash": dash_style, "width": width})
    markers.legend(fig, POINTS.values(), "legend2", "#444")
    for t in TYPES:
        style.legend_key(fig, t, "legend3", mode="markers",
                         marker={"symbol": "square", "size": 13, "color": style.SHIMMY_TYPE_COLOURS[t],
                                 "opacity": 0.75, "line": {"width": 1, "color": "#888"}})
    fig.update_xaxes(range=list(v_range))
    fig.update_yaxes(range=list(fz_range))
    # the curves-and-points row wraps onto a second line at 1024 px: the shading row starts below it; long
    # design names wrap the first row too: the figure grows by the lines they take (the plot keeps its size)
    style.legends(fig, [f"{what} (colour)", "curves, points", "shimmy type (shading)"], HEIGHT, BOTTOM,
                  rows=[1, 1.45, 1], first_names=[label for label, _ in series])


def _regions(fig, result, opacity):
    for region in result.get("regions") or []:
        fig.add_scatter(x=region["V"], y=[f / units.KN for f in region["Fz"]], mode="lines", fill="toself",
                        fillcolor=style.SHIMMY_TYPE_COLOURS[region["type"]], opacity=opacity, line={"width": 0},
                        hoverinfo="skip", showlegend=False, name=region["type"])


def sketch_figure(sketches, previous=None, live=False):
    """The maps being made as far as they are known: their Hopf curves, then each fold and torus
    curve as it is continued, before the slices and the shading are done; over the previous
    design's map, faint (its regions pale, its curves thin), when the map follows the design."""
    known = [s for s in sketches if s]
    series = [(style.CONFIG_LABELS[s["config"]], style.CONFIG_COLOURS[s["config"]]) for s in known]
    curves = sum(len(s["fold_curves"]) + len(s["torus_curves"]) for s in known)
    what = "the new design's map" if live else "the map"
    done = ("Hopf curves so far; the fold and torus curves, then the shading, follow" if not curves
            else f"Hopf curves and {curves} fold / torus curve{'s' if curves != 1 else ''} so far; the shading follows")
    fig = style.figure("", "forward speed V (m/s)", "vertical load Fz (kN)", height=HEIGHT)
    style.titled(fig, f"Making {what}", done)  # (one line was cut at 1024 px)
    v_range = known[0]["v_range"]
    fz_range = [f / units.KN for f in known[0]["fz_range"]]
    before = [r for r in previous or [] if r.get("config") == known[0]["config"]  # the same map, earlier
              and r.get("v_range") == known[0]["v_range"] and r.get("fz_range") == known[0]["fz_range"]][:1]
    if before:
        _regions(fig, before[0], FAINT_REGIONS)
        _curves(fig, before, [(f"{label} (previous)", colour) for label, colour in
                              ((style.CONFIG_LABELS[r["config"]], style.CONFIG_COLOURS[r["config"]]) for r in before)],
                "previous", faint=True)
    _curves(fig, known, series, "configuration")
    inside = [(name, v, f) for name, (v, f) in ui.OPERATING_POINTS.items()
              if v_range[0] <= v <= v_range[1] and fz_range[0] <= f <= fz_range[1]]
    _finish(fig, series, "configuration", inside, v_range, fz_range)
    return fig


def _pct(value, base):
    """Relative change against original, for the table."""
    return "–" if value is None or not base else formats.signed_percent(100 * (value - base) / base, 1)


def summary(results):
    base = next((r for r in results if r["config"] == "original"), None)
    rows = []
    for r in results:
        m = r["metrics"]
        at = m["at_Fz"]
        hull = at["shimmy_speed_range"]
        low = None if r["min_shimmy_Fz"] is None else r["min_shimmy_Fz"] / units.KN
        speeds = "–" if hull is None else f"{hull[0]:.4g} – {hull[1]:.4g}"
        row = [style.CONFIG_LABELS[r["config"]], formats.significant(low), formats.significant(m["torsion_area"], 5),
               speeds, formats.significant(at["max_psi"]), len(r["gh_points"]), len(r["fold_curves"]),
               len(r["torus_curves"])]
        if base is not None and r is not base:
            b = base["metrics"]
            row[1] += f" ({_pct(r['min_shimmy_Fz'], base['min_shimmy_Fz'])})"
            row[2] += f" ({_pct(m['torsion_area'], b['torsion_area'])})"
            row[4] += f" ({_pct(at['max_psi'], b['at_Fz']['max_psi'])})"
        rows.append(row)
    fz = results[0]["metrics"]["at_Fz"]["Fz"] / units.KN
    area = f"{merits.label('torsion_area')} ({merits.unit('torsion_area')})"
    return ui.table(["configuration", "min shimmy Fz (kN)", area, f"shimmy V at {fz:g} kN (m/s)",
                     f"max stable |psi| at {fz:g} kN (rad)", f"{PointKind.GENERALISED_HOPF} points",
                     "fold curves", "torus curves"], rows, ids.MAP_SUMMARY)


def _cached(analysis, requests):
    """The first shown result of a section (its requests store, as the browser sent it back), from the cache."""
    wanted = requests.get("requests") if isinstance(requests, dict) else requests
    if not isinstance(wanted, list) or not wanted:
        return None
    try:
        return analyses.cached(analysis, wanted[0])
    except InvalidParameterError:
        return None


def _kick_text(point, max_size):
    """A cell's margin in words (the hover text)."""
    if point["margin"] is None:
        return f"no yaw kick up to {max_size:g} rad reaches torsional shimmy"
    if point["margin"] == 0.0:
        return "0: the standard start (psi = 0.001 rad) already ends on torsional shimmy"
    return (f"min yaw kick to torsional shimmy: {point['margin']:.3g} rad (± {point['tolerance']:.1g})"
            + ("" if point["confirmed"] else "; not confirmed by its check runs"))


def margin_grid(result):
    """The margins of a margin map on the regular grid of its cells' centres: (V in m/s, Fz in kN, z) with z[j][i]
    the margin (rad) of the cell at (V[i], Fz[j]), NaN where there is none (a cell not computed: one attractor or
    no torsional cycle there; or no kick up to the largest reaching torsional shimmy)."""
    V, Fz = result["V"], result["Fz"]
    z = [[math.nan] * len(V) for _ in Fz]
    for p in result["points"]:
        if p["margin"] is not None:
            i = min(range(len(V)), key=lambda k: abs(V[k] - p["V"]))
            j = min(range(len(Fz)), key=lambda k: abs(Fz[k] - p["Fz"]))
            z[j][i] = p["margin"]
    return list(V), [f / units.KN for f in Fz], z


def margin_levels(low, high):
    """The iso-margin levels (rad) strictly between the margins ``low`` and ``high``, evenly spaced by the largest
    round step (MARGIN_STEPS) that gives at least MARGIN_LEVELS of them (so 4 to 8); none if ``high`` is not above
    ``low``."""
    if not high > low:
        return []
    for k in range(math.floor(math.log10(high - low)), -16, -1):
        for step in MARGIN_STEPS:
            size = step * 10.0 ** k
            first, last = math.floor(low / size) + 1, math.ceil(high / size) - 1
            if last - first + 1 >= MARGIN_LEVELS:
                return [float(f"{n * size:.12g}") for n in range(first, last + 1)]
    return []


def _cropped(V, Fz, z):
    """The grid cut to the rows and columns that hold a margin (Plotly fills the empty cells to draw, then hides
    them: less of a line is drawn where it cannot be seen)."""
    rows = [j for j, row in enumerate(z) if any(not math.isnan(m) for m in row)]
    columns = [i for i in range(len(V)) if any(not math.isnan(row[i]) for row in z)]
    if not rows:
        return [], [], []
    rows, columns = range(rows[0], rows[-1] + 1), range(columns[0], columns[-1] + 1)
    return [V[i] for i in columns], [Fz[j] for j in rows], [[z[j][i] for i in columns] for j in rows]


def _square(z):
    """Whether some square of four neighbouring cells holds three or more margins (Plotly draws a contour only
    there: it clips its lines to the cells that have a value)."""
    return any(sum(not math.isnan(z[j + a][i + b]) for a in (0, 1) for b in (0, 1)) >= 3
               for j in range(len(z) - 1) for i in range(len(z[0]) - 1))


def _crossings(z, level, levels):
    """Where the line of ``level`` crosses the edge between two neighbouring cells with margins (so where it is
    drawn): (row, column) as fractional indices of z, the levels crossing that edge, the cells with margins at
    its ends and beside it (row, column)."""
    def has(j, i):
        return 0 <= j < len(z) and 0 <= i < len(z[0]) and not math.isnan(z[j][i])

    for j, i, (dj, di) in itertools.product(range(len(z)), range(len(z[0])), ((0, 1), (1, 0))):
        if has(j, i) and has(j + dj, i + di) and (z[j][i] - level) * (z[j + dj][i + di] - level) < 0:
            a, b = z[j][i], z[j + dj][i + di]
            t = (level - a) / (b - a)
            near = [(j + dj * e + di * s, i + di * e + dj * s) for e in (0, 1) for s in (-1, 0, 1)]
            yield (j + t * dj, i + t * di), sum((a - m) * (b - m) < 0 for m in levels), [c for c in near if has(*c)]


def _gap(a, b, cell):
    """How far apart two boxes ((row, column), (width, height) px) are, on cells of ``cell`` (width, height) px:
    as a multiple of the distance at which they would touch (below 1: they overlap)."""
    ((ya, xa), (wa, ha)), ((yb, xb), (wb, hb)) = a, b
    return max(abs(xa - xb) * cell[0] / ((wa + wb) / 2), abs(ya - yb) * cell[1] / ((ha + hb) / 2))


def _label_places(z, levels, cell, marker):
    """Where to write each level on its line, as (level, (row, column)) in fractional indices of z: on an edge
    that line crosses between two cells with margins, over no label placed before (a level without such a place
    goes unlabelled), best over none of the markers (``marker`` px on cells of ``cell`` px), inside the cells with
    margins, crossed by no other line and away from the other labels. (Plotly's own labels, ``showlabels``, are
    placed along the whole line, the part it hides over the empty cells too: some came out cut or unseen.)"""
    placed = []
    for level in levels:
        box = (LABEL_PX[0] * len(f"{level:g}") + 4, LABEL_PX[1])
        best, most = None, -math.inf
        for at, lines, near in _crossings(z, level, levels):
            apart = min((_gap((at, box), other, cell) for _, other in placed), default=3.0)
            covered = sum(_gap((at, box), (c, (marker, marker)), cell) < 1 for c in near)
            score = len(near) - 2 * covered - (lines - 1) + min(apart, 3.0)
            if apart >= 1 and score > most:
                best, most = at, score
        if best is not None:
            placed.append((level, (best, box)))
    return [(level, at) for level, (at, _) in placed]


def _at(axis, k):
    """The value at the fractional index ``k`` of an evenly spaced ``axis``."""
    return axis[0] + k * (axis[1] - axis[0]) if len(axis) > 1 else axis[0]


def _margin_lines(fig, result):
    """Iso-margin lines over the cells with margins, each labelled in rad, over a white halo (no hover: the
    markers keep theirs; no colour bar: the markers' says rad). None where nothing is to contour: no square of
    neighbouring cells with margins, or all margins equal within twice the largest margin's tolerance."""
    V, Fz, z = _cropped(*margin_grid(result))
    reached = [m for row in z for m in row if not math.isnan(m)]
    low, high = min(reached, default=0.0), max(reached, default=0.0)
    # margins within their own bisection tolerances of each other: lines would draw the tolerance, not the margin
    noise = 2.0 * max((p["tolerance"] or 0.0 for p in result["points"] if p["margin"]), default=0.0)
    levels = margin_levels(low, high) if high - low > noise else []
    if not levels or not _square(z):
        return
    contours = {"coloring": "lines", "start": levels[0], "end": levels[-1],
                "size": float(f"{levels[1] - levels[0]:.12g}"), "showlabels": False}
    for name, line in (("iso-margin halo", style.halo(MARGIN_LINES["width"])), ("iso-margin lines", MARGIN_LINES)):
        fig.add_contour(x=V, y=Fz, z=z, connectgaps=False, showscale=False, hoverinfo="skip", zorder=1, name=name,
                        colorscale=[[0, line["color"]], [1, line["color"]]], line={"width": line["width"]},
                        contours=contours)
    cell = (PLOT_PX[0] / result["grid"]["n_v"], PLOT_PX[1] / result["grid"]["n_fz"])
    for level, (y, x) in _label_places(z, levels, cell, _marker_size(result)):
        fig.add_annotation(x=_at(V, x), y=_at(Fz, y), text=f"{level:g}", showarrow=False, name="iso-margin label",
                           font={"size": 11, "color": MARGIN_LINES["color"]}, bgcolor="rgba(255,255,255,0.85)",
                           borderpad=1)


def _marker_size(result):
    """A margin's marker (px): as large as the cells allow (the plot is some 500 px high and 500-900 px wide)."""
    return max(6.0, min(18.0, 360.0 / result["grid"]["n_v"], 240.0 / result["grid"]["n_fz"]))


def margin_figure(result, smap=None, why=""):
    """The margins of a margin map as coloured markers at the cells' centres (a colour bar in rad: dark, a small
    kick; their margins on hover) under labelled iso-margin contour lines (a round step between them, drawn over
    the cells with margins only) over the map's regions and curves (``smap``: the shown map of the same
    configuration, design and plane, if any, else ``why`` not in the title); crosses where no kick up to the
    largest reaches torsional shimmy."""
    label, colour = style.CONFIG_LABELS[result["config"]], style.CONFIG_COLOURS[result["config"]]
    series = [(label, colour)]
    max_size = result["options"]["max_size"]
    reached = [p for p in result["points"] if p["margin"] is not None]
    crossed = [p for p in result["points"] if p["margin"] is None]
    sub = (f"from straight rolling, in the {len(result['points'])} cells where it coexists with another attractor"
           + ("" if smap is not None else f"<br>({why or 'compute the map above to see its regions under them'})"))
    fig = style.figure("", "forward speed V (m/s)", "vertical load Fz (kN)", height=HEIGHT)
    style.titled(fig, f"{label}: smallest yaw kick to torsional shimmy", sub)
    if smap is not None:
        _regions(fig, smap, MARGIN_REGIONS)
        _curves(fig, [smap], series, "configuration")
    size = _marker_size(result)
    fig.add_scatter(x=[p["V"] for p in reached], y=[p["Fz"] / units.KN for p in reached], mode="markers",
                    name="min yaw kick", showlegend=False, customdata=[_kick_text(p, max_size) for p in reached],
                    marker={"size": size, "symbol": "square", "color": [p["margin"] for p in reached],
                            "colorscale": "Viridis", "cmin": 0.0,
                            "cmax": max([p["margin"] for p in reached], default=max_size) or max_size,
                            "line": {"width": 1, "color": "#fff"},
                            "colorbar": {"title": {"text": "min yaw kick (rad)", "side": "right"}, "thickness": 14,
                                         "len": 0.6, "y": 0.62}},
                    hovertemplate="V %{x:.4g} m/s<br>Fz %{y:.4g} kN<br>%{customdata}<extra>click: time history"
                                  "</extra>")
    _margin_lines(fig, result)
    if crossed:
        fig.add_scatter(x=[p["V"] for p in crossed], y=[p["Fz"] / units.KN for p in crossed], mode="markers",
                        marker={"symbol": "x-thin", "size": size * 0.8, "line": {"width": 2, "color": "#333"}},
                        name=f"none up to {max_size:g} rad", legend="legend2",
                        customdata=[_kick_text(p, max_size) for p in crossed],
                        hovertemplate="V %{x:.4g} m/s<br>Fz %{y:.4g} kN<br>%{customdata}<extra></extra>")
    inside = [(name, v, f) for name, (v, f) in ui.OPERATING_POINTS.items()
              if result["v_range"][0] <= v <= result["v_range"][1]
              and result["fz_range"][0] <= f * units.KN <= result["fz_range"][1]]
    _finish(fig, series, "configuration", inside, tuple(result["v_range"]),
            tuple(f / units.KN for f in result["fz_range"]))
    return fig


def margin_table(result):
    """Per load: the cells computed, those the standard start already takes to torsional shimmy (margin 0), the
    smallest margin above 0 and the largest (and where), those not reached, those not confirmed."""
    rows = []
    for f in result["Fz"]:
        here = [p for p in result["points"] if p["Fz"] == f]
        if not here:
            continue
        above = [p for p in here if p["margin"]]
        low = min(above, key=lambda p: p["margin"]) if above else None
        high = max(above, key=lambda p: p["margin"]) if above else None
        rows.append([formats.significant(f / units.KN), len(here), sum(p["margin"] == 0.0 for p in here),
                     "–" if low is None else f"{formats.significant(low['margin'], 3)} at {low['V']:.4g} m/s",
                     "–" if high is None else f"{formats.significant(high['margin'], 3)} at {high['V']:.4g} m/s",
                     sum(p["margin"] is None for p in here), sum(p["confirmed"] is False for p in here)])
    c = result["counts"]
    note = html.P(f"{c['multistable']} of {c['cells']} cells hold two or more attractors ({c['bistable']} Bistable); "
                  f"{c['computed']} with a torsional cycle computed, {c['runs']} runs in {result['elapsed_s']:.0f} s. "
                  f"Worst shimmy: {result['worst']}. Each margin within {result['options']['rtol']:g} of itself.",
                  className="hint")
    return [note, ui.table(["Fz (kN)", "cells", "0: the standard start's", "smallest kick above 0 (rad)",
                            "largest kick (rad)", f"none up to {result['options']['max_size']:g} rad",
                            "not confirmed"], rows, ids.MAPM_SUMMARY)]


@dash.callback(Output(ids.MAPM_GRAPH, "figure"), Input(ids.MAPM.requests, "data"),
               Input(ids.MAP_GROUP.requests, "data"))
def draw_margins(margin_requests, map_requests):
    """The margins shown (the section's requests store), over the map shown above when it is of the same
    configuration, design and plane (from the cache: nothing is computed here)."""
    result = _cached("margin_map", margin_requests)
    if result is None:
        return style.message_figure(MARGIN_WAITING, 360)
    smap = _cached("map", map_requests)
    same = smap is not None and all(smap[k] == result[k] for k in ("config", "params", "v_range", "fz_range"))
    why = "" if smap is None else "the map above is of another configuration, plane or design: not drawn under them"
    return margin_figure(result, smap if same else None, why)


@dash.callback(Output(ids.MAPM_NAV, "href"), Output(ids.MAPM_HINT, "children"),
               Input(ids.MAPM_GRAPH, "clickData"), State(ids.MAPM.requests, "data"), prevent_initial_call=True)
def open_kick(click, requests):
    """A click on a cell opens its time history from just above its smallest kick to torsional shimmy (the
    check run's start, for as long as the check ran), or from the standard start where the margin is 0."""
    result = _cached("margin_map", requests)
    if not click or not click.get("points") or result is None:
        return no_update, no_update
    V, fz_kn = float(click["points"][0]["x"]), float(click["points"][0]["y"])
    point = min(result["points"], key=lambda p: abs(p["V"] - V) / 10 + abs(p["Fz"] / units.KN - fz_kn) / 100,
                default=None)
    if (point is None or abs(point["V"] - V) > 1e-6 * max(1.0, V)
            or abs(point["Fz"] / units.KN - fz_kn) > 1e-6 * fz_kn):
        return no_update, no_update
    query = {"config": result["config"], "V": f"{point['V']:.6g}", "Fz": f"{point['Fz'] / units.KN:.6g}",
             "run": "1", "map_type": point["type"]}
    kick = ""
    if point["margin"]:
        query.update(psi0=f"{point['upper']:.6g}", t_end=f"{result['options']['t_max']:g}")
        kick = f" from psi0 = {point['upper']:.4g} rad, just above its smallest kick to torsional shimmy"
    query.update({k: f"{v:.10g}" for k, v in (result.get("params") or {}).items()})
    return ("/time-history?" + urlencode(query),
            f"Opening the time history at V = {point['V']:.4g} m/s, Fz = {point['Fz'] / units.KN:.4g} kN{kick}")


@dash.callback(Output(ids.MAP_NAV, "href"), Output(ids.MAP_HINT, "children"),
               Input(ids.MAP_GRAPH, "clickData"), State(ids.MAP_GROUP.requests, "data"), prevent_initial_call=True)
def open_time_history(click, requests):
    """A click on the map opens the time history at that point (same configuration and design)."""
    if not click or not requests or not click.get("points"):
        return no_update, no_update
    point = click["points"][0]
    V, fz_kn = float(point["x"]), float(point["y"])
    request = requests[0]
    query = {"config": request["config"], "V": f"{V:.6g}", "Fz": f"{fz_kn:.6g}", "run": "1"}
    if point.get("customdata") in TYPES:  # the shading's type there (the time history says if it is Bistable)
        query["map_type"] = point["customdata"]
    query.update({k: f"{v:.10g}" for k, v in (request.get("params") or {}).items()})
    if request.get("material") not in (None, "steel"):
        query["material"] = request["material"]
    return "/time-history?" + urlencode(query), f"Opening the time history at V = {V:.4g} m/s, Fz = {fz_kn:.4g} kN"


@dash.callback(Output(ids.URL_UPDATE, "data", allow_duplicate=True),
               Input(ids.MAP_SHADE, "value"), Input(ids.MAP_OVERLAY, "value"), Input(ids.MAP_FZMIN, "value"),
               Input(ids.MAP_FZMAX, "value"), Input(ids.MAP_VMIN, "value"), Input(ids.MAP_VMAX, "value"),
               Input(ids.MAP_RES, "value"), Input(ids.MAPC_CONFIG, "value"), Input(ids.MAPC_FZ, "value"),
               Input(ids.MAPM_NV, "value"), Input(ids.MAPM_NFZ, "value"), Input(ids.MAPM_MAX, "value"),
               prevent_initial_call=True)
def remember(shade, overlay, fz_min, fz_max, v_min, v_max, resolution, compared, merit_fz, n_v, n_fz, max_size):
    return {"shade": shade, "overlay": ",".join(overlay or []), "fz_min": fz_min, "fz_max": fz_max, "v_min": v_min,
            "v_max": v_max, "resolution": resolution, "compare_config": None if compared == "nes_pd" else compared,
            "compare_fz": None if merit_fz == 150 else merit_fz,
            **{key: None if value == q.spec.default else value for key, q, value in (
                ("margin_nv", CELLS_V, n_v), ("margin_nfz", CELLS_FZ, n_fz), ("margin_max", MAX_KICK, max_size))}}
