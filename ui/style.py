"""Colours and figure defaults shared by every page (Okabe–Ito, colour-blind safe)."""

from __future__ import annotations

import math

import plotly.graph_objects as go
import plotly.io as pio

CONFIG_COLOURS = {"original": "#000000", "nes": "#E69F00", "pd": "#0072B2", "nes_pd": "#009E73"}
CONFIG_LABELS = {"original": "original", "nes": "NES", "pd": "PD", "nes_pd": "NES + PD"}
#: The shading of a map's regions. Torsion is Okabe–Ito yellow, not the NES's orange: a NES curve drawn over
#: the torsion lobe stays visible (and every curve has a halo, :data:`HALO`); Both a dark green; Latent (straight
#: rolling stable beside a stable cycle) a grey.
SHIMMY_TYPE_COLOURS = {"Stable": "#FFFFFF", "Torsion": "#F0E442", "Lateral": "#56B4E9", "Bistable": "#CC79A7",
                       "Both": "#117733", "Latent": "#AAAAAA"}
#: One colour per compared design (dark and saturated: readable on white and over the map's shading,
#: apart from the configurations' colours, which stay with the configurations).
DESIGN_COLOURS = ("#1A1A1A", "#D55E00", "#0057B8", "#A0329A")
ACCENT = "#0072B2"
#: The halo under a curve drawn over shading: a white line this much wider (px), so that the curve reads on
#: every region colour (:func:`halo`).
HALO = {"color": "rgba(255,255,255,0.9)", "extra": 3.0}
#: Axes without SI prefixes: an engineering axis in m reads 0.0004, never "400µ" (exponentformat "none"),
#: on every axis of every figure (a template's layout.xaxis applies to every x axis of the figure).
_AXIS = {"exponentformat": "none", "separatethousands": False}
TEMPLATE = go.layout.Template(pio.templates["plotly_white"])
TEMPLATE.layout.xaxis.update(_AXIS)
TEMPLATE.layout.yaxis.update(_AXIS)
TEMPLATE.data.heatmap = [go.Heatmap(colorbar={"exponentformat": "none"})]
TEMPLATE.data.scatter = [go.Scatter(marker={"colorbar": {"exponentformat": "none"}})]
#: The same for the plain-dict figures redrawn on every slider move (no template to send each time).
LIGHT_TEMPLATE = {"layout": {"xaxis": dict(_AXIS), "yaxis": dict(_AXIS)}}
#: Log-speed axes: the ticks 1, 2, 5, 10, 20, 50, 100, 200 m/s written out (not "2" for 20 and 200).
LOG_SPEED_TICKS = [1, 2, 5, 10, 20, 50, 100, 200, 500]
LOG_SPEED_AXIS = {"type": "log", "tickvals": LOG_SPEED_TICKS, "ticktext": [f"{v:g}" for v in LOG_SPEED_TICKS],
                  "tickformat": "~g"}
#: The hover text of an angle: rad, then degrees from the trace's customdata (:func:`in_degrees`).
ANGLE_HOVER = "%{y:.4g} rad (%{customdata:.3g}°)"
#: Characters a line of a placeholder's text: its plot is some 600 px wide at a 1024 px window.
MESSAGE_WIDTH = 72
#: Room above the plot for the figure toolbar and, below it, the title (they never overlap).
MARGIN = {"l": 64, "r": 16, "t": 76, "b": 52}


def title(text: str, subtitle: str | None = None) -> dict:
    """A title just above the plot area, left-aligned: under the toolbar at the top right, whatever the width.
    Plotly does not wrap a title: one longer than a 1024 px window's plot (about 70 characters) says what
    the figure is in ``text`` and the rest in ``subtitle``, smaller, under it (lines split by ``<br>``;
    :data:`SUBTITLE_LINE` px each, for the top margin)."""
    out = {"text": text, "x": 0, "xref": "paper", "xanchor": "left", "y": 1, "yref": "paper", "yanchor": "bottom",
           "pad": {"b": 12}, "font": {"size": 15}}
    if subtitle:  # drawn under the title's line: the title stands that much higher above the plot
        out["subtitle"] = {"text": subtitle, "font": {"size": 12, "color": "#444"}}
        out["pad"] = {"b": 12 + SUBTITLE_LINE * (subtitle.count("<br>") + 1)}
    return out


#: the height (px) of a line of a title's subtitle
SUBTITLE_LINE = 17


def titled(fig, text: str, subtitle: str | None = None) -> None:
    """Give ``fig`` the house :func:`title` (with ``subtitle``, if any) and a top margin that makes room for
    the subtitle's lines above the plot."""
    lines = subtitle.count("<br>") + 1 if subtitle else 0
    fig.update_layout(title=title(text, subtitle), margin={"t": MARGIN["t"] + SUBTITLE_LINE * lines})


_title = title


def figure(title: str, x: str, y: str, height: int = 380) -> go.Figure:
    """An empty figure with axis titles (units included by the caller) and the house style."""
    fig = go.Figure()
    fig.update_layout(title=_title(title), height=height, margin=MARGIN, template=TEMPLATE,
                      legend={"orientation": "h", "y": -0.22, "x": 0}, hovermode="closest",
                      font={"family": "system-ui, -apple-system, Segoe UI, Roboto, sans-serif", "size": 12})
    fig.update_xaxes(title_text=x, showline=True, linecolor="#888", mirror=True, zeroline=False)
    fig.update_yaxes(title_text=y, showline=True, linecolor="#888", mirror=True, zeroline=False)
    return fig


def message_figure(text: str, height: int = 300) -> go.Figure:
    fig = go.Figure()
    fig.add_annotation(text=wrapped(text, MESSAGE_WIDTH), showarrow=False, x=0.5, y=0.5, xref="paper", yref="paper",
                       font={"size": 14, "color": "#555"})
    fig.update_layout(height=height, template=TEMPLATE, xaxis={"visible": False}, yaxis={"visible": False},
                      margin={"l": 10, "r": 10, "t": 10, "b": 10})
    return fig


def wrapped(text: str, width: int = 80) -> str:
    """``text`` broken into lines of at most ``width`` characters with <br> (a Plotly annotation does not
    wrap: at 1024 px a long line is clipped at the figure's edges)."""
    lines, line = [], ""
    for word in text.split():
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    return "<br>".join(lines + [line] if line else lines)


def in_degrees(values) -> list:
    """Angles (rad) in degrees, for the customdata of :data:`ANGLE_HOVER` (None stays None)."""
    return [None if v is None else math.degrees(v) for v in values]


def halo(width: float) -> dict:
    """The line drawn under a curve of ``width`` px over shading (same points, no hover, no legend)."""
    return {"color": HALO["color"], "width": width + HALO["extra"]}


def layout(title: str, x: str, y: str, height: int = 380, x_log: bool = False) -> dict:
    """The house layout as a plain dict (for figures rebuilt on every slider move: no validation cost)."""
    axis = {"showline": True, "linecolor": "#888", "mirror": True, "zeroline": False, "gridcolor": "#e5e8ef", **_AXIS}
    return {"title": _title(title), "height": height, "margin": dict(MARGIN), "template": LIGHT_TEMPLATE,
            "legend": {"orientation": "h", "y": -0.22, "x": 0}, "hovermode": "closest",
            "font": {"family": "system-ui, -apple-system, Segoe UI, Roboto, sans-serif", "size": 12},
            "plot_bgcolor": "#ffffff", "paper_bgcolor": "#ffffff",
            "xaxis": {**axis, "title": {"text": x}, **(LOG_SPEED_AXIS if x_log else {"type": "linear"})},
            "yaxis": {**axis, "title": {"text": y}}}


def legend_key(fig, name: str, legend: str = "legend", group: str | None = None, **trace) -> None:
    """A legend entry that draws nothing (its meaning is shared by many traces: a colour, a line
    style, a marker kind). ``group``: the legendgroup of the traces it stands for (a click toggles them)."""
    fig.add_scatter(x=[None], y=[None], name=name, legend=legend, legendgroup=group or f"key-{legend}-{name}",
                    showlegend=True, hoverinfo="skip", **trace)


LEGEND_ROW = 34  # px from one legend row to the next: one line of entries and its wrap at 1024 px


#: the width (px) a legend row has at a 1024 px window, and what its title and each entry take
LEGEND_WIDTH, LEGEND_TITLE_CHAR, LEGEND_ENTRY, LEGEND_CHAR = 560, 7.0, 52, 6.6


def legend_lines(title: str, names: list[str]) -> int:
    """How many lines a legend row titled ``title`` with entries ``names`` takes at a 1024 px window
    (Plotly wraps a horizontal legend; an estimate from the characters, on the safe side): design
    names typed by a user (up to 80 characters each) wrap where configuration names do not."""
    width, lines = LEGEND_TITLE_CHAR * (len(title) + 2), 1
    for name in names:
        entry = LEGEND_ENTRY + LEGEND_CHAR * len(name)
        if width + entry > LEGEND_WIDTH and width > 0:
            lines, width = lines + 1, 0.0
        width += entry
    return lines


def legends(fig, titles: list[str], height: int, bottom: int, rows: list[float] | None = None,
            first_names: list[str] | None = None) -> None:
    """Separate legends (legend, legend2, ...) stacked under the plot, each with its title on its left:
    which colour is which configuration apart from what a line style or a marker kind means.
    ``bottom`` is the figure's bottom margin (px) they live in; ``rows`` gives each legend's height
    in rows of ``LEGEND_ROW`` px (1 each by default; more for a legend whose entries wrap onto a
    further line at 1024 px, so the next one starts below its last line). ``first_names``: the first
    legend's entries where they are the user's (design names): that row takes the lines they take
    (:func:`legend_lines`), and the figure's height and bottom margin grow by them (the plot keeps its
    size). The figure's height and bottom margin are set here."""
    rows = [1.0] * len(titles) if rows is None else list(rows)
    if len(rows) != len(titles):
        raise ValueError(f"legends: {len(rows)} row heights for {len(titles)} legends")
    if first_names is not None:
        rows[0] = legend_lines(titles[0], first_names)
        extra = int(LEGEND_ROW * (rows[0] - 1))
        height, bottom = height + extra, bottom + extra
    fig.update_layout(height=height, margin={"b": bottom})
    layout = {}
    y_px = bottom - 54
    for k, text in enumerate(titles):
        key = "legend" if k == 0 else f"legend{k + 1}"
        if k:
            y_px -= LEGEND_ROW * rows[k - 1]
        layout[key] = {"title": {"text": text + ":", "side": "left"}, "orientation": "h", "x": 0, "xanchor": "left",
                       "y": y_px / height, "yref": "container", "yanchor": "top", "font": {"size": 11},
                       "bgcolor": "rgba(255,255,255,0)", "tracegroupgap": 4}
    fig.update_layout(**layout)
