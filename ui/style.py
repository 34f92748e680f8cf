"""Colours and figure defaults shared by every page (Okabe–Ito, colour-blind safe)."""

from __future__ import annotations

import plotly.graph_objects as go

CONFIG_COLOURS = {"original": "#000000", "nes": "#E69F00", "pd": "#0072B2", "nes_pd": "#009E73"}
CONFIG_LABELS = {"original": "original", "nes": "NES", "pd": "PD", "nes_pd": "NES + PD"}
SHIMMY_TYPE_COLOURS = {"Stable": "#FFFFFF", "Torsion": "#E69F00", "Lateral": "#56B4E9", "Bistable": "#CC79A7",
                       "Both": "#117733"}  # Both: a dark green, far from Torsion's orange
#: One colour per compared design (dark and saturated: readable on white and over the map's shading,
#: apart from the configurations' colours, which stay with the configurations).
DESIGN_COLOURS = ("#1A1A1A", "#D55E00", "#0057B8", "#A0329A")
ACCENT = "#0072B2"
#: Room above the plot for the figure toolbar and, below it, the title (they never overlap).
MARGIN = {"l": 64, "r": 16, "t": 76, "b": 52}


def title(text: str) -> dict:
    """A title just above the plot area, left-aligned: under the toolbar at the top right, whatever the width."""
    return {"text": text, "x": 0, "xref": "paper", "xanchor": "left", "y": 1, "yref": "paper", "yanchor": "bottom",
            "pad": {"b": 12}, "font": {"size": 15}}


_title = title


def figure(title: str, x: str, y: str, height: int = 380) -> go.Figure:
    """An empty figure with axis titles (units included by the caller) and the house style."""
    fig = go.Figure()
    fig.update_layout(title=_title(title), height=height, margin=MARGIN, template="plotly_white",
                      legend={"orientation": "h", "y": -0.22, "x": 0}, hovermode="closest",
                      font={"family": "system-ui, -apple-system, Segoe UI, Roboto, sans-serif", "size": 12})
    fig.update_xaxes(title_text=x, showline=True, linecolor="#888", mirror=True, zeroline=False)
    fig.update_yaxes(title_text=y, showline=True, linecolor="#888", mirror=True, zeroline=False)
    return fig


def message_figure(text: str, height: int = 300) -> go.Figure:
    fig = go.Figure()
    fig.add_annotation(text=text, showarrow=False, x=0.5, y=0.5, xref="paper", yref="paper",
                       font={"size": 14, "color": "#555"})
    fig.update_layout(height=height, template="plotly_white", xaxis={"visible": False}, yaxis={"visible": False},
                      margin={"l": 10, "r": 10, "t": 10, "b": 10})
    return fig


def layout(title: str, x: str, y: str, height: int = 380, x_log: bool = False) -> dict:
    """The house layout as a plain dict (for figures rebuilt on every slider move: no validation cost)."""
    axis = {"showline": True, "linecolor": "#888", "mirror": True, "zeroline": False, "gridcolor": "#e5e8ef"}
    return {"title": _title(title), "height": height, "margin": dict(MARGIN), "template": "plotly_white",
            "legend": {"orientation": "h", "y": -0.22, "x": 0}, "hovermode": "closest",
            "font": {"family": "system-ui, -apple-system, Segoe UI, Roboto, sans-serif", "size": 12},
            "plot_bgcolor": "#ffffff", "paper_bgcolor": "#ffffff",
            "xaxis": {**axis, "title": {"text": x}, "type": "log" if x_log else "linear"},
            "yaxis": {**axis, "title": {"text": y}}}


def legend_key(fig, name: str, legend: str = "legend", group: str | None = None, **trace) -> None:
    """A legend entry that draws nothing (its meaning is shared by many traces: a colour, a line
    style, a marker kind). ``group``: the legendgroup of the traces it stands for (a click toggles them)."""
    fig.add_scatter(x=[None], y=[None], name=name, legend=legend, legendgroup=group or f"key-{legend}-{name}",
                    showlegend=True, hoverinfo="skip", **trace)


def legends(fig, titles: list[str], height: int, bottom: int) -> None:
    """Separate legends (legend, legend2, ...) stacked under the plot, each with its title on its left:
    which colour is which configuration apart from what a line style or a marker kind means.
    ``bottom`` is the figure's bottom margin (px) they live in."""
    layout = {}
    for k, text in enumerate(titles):
        key = "legend" if k == 0 else f"legend{k + 1}"
        y_px = bottom - 54 - 34 * k  # room for one wrapped line at 1024 px
        layout[key] = {"title": {"text": text + ":", "side": "left"}, "orientation": "h", "x": 0, "xanchor": "left",
                       "y": y_px / height, "yref": "container", "yanchor": "top", "font": {"size": 11},
                       "bgcolor": "rgba(255,255,255,0)", "tracegroupgap": 4}
    fig.update_layout(**layout)
