"""One marker per kind of special point, on every page (Overview, Bifurcation diagram, Stability map,
Parametric study, Ground run): a diamond is always a Hopf point, a star always a generalised Hopf
point, whatever the page. The labels are the continuation tools' (:class:`PointKind`), the symbols
Plotly's. The pages build every special-point marker and its legend entry from here.
"""

from __future__ import annotations

from dataclasses import dataclass

from shimmy.continuation.kinds import PointKind

from . import style


@dataclass(frozen=True)
class Marker:
    """How a kind of point is drawn: its label (the tools'), its name in words, Plotly's symbol, its size (px)."""

    label: str
    name: str
    symbol: str
    size: int = 11

    @property
    def legend(self) -> str:
        """The legend's entry: "H: Hopf"."""
        return f"{self.label}: {self.name}"


#: The vocabulary: each kind of special point with its marker.
MARKERS: dict[str, Marker] = {
    PointKind.HOPF: Marker("H", "Hopf", "diamond", 11),
    PointKind.GENERALISED_HOPF: Marker("GH", "generalised Hopf", "star", 14),
    PointKind.DOUBLE_HOPF: Marker("HH", "double Hopf", "hexagram", 14),
    PointKind.FOLD_OF_CYCLES: Marker("LPC", "fold of cycles", "triangle-up", 11),
    PointKind.TORUS: Marker("NS", "torus", "square", 10),
    PointKind.PERIOD_DOUBLING: Marker("PD", "period doubling", "x", 11),
    PointKind.BRANCH_POINT_OF_CYCLES: Marker("BPC", "branch point of cycles", "cross", 11),
    PointKind.BRANCH_POINT: Marker("BP", "branch point", "circle-open", 10),
    PointKind.ZERO_HOPF: Marker("ZH", "zero-Hopf", "pentagon", 12),
    PointKind.FOLD: Marker("LP", "fold", "triangle-down", 11),
    PointKind.ZERO_AMPLITUDE: Marker("ZA", "cycles shrinking onto straight rolling", "circle-x-open", 10),
    PointKind.P2_TURN: Marker("turn", "turn in the parameter", "triangle-right", 10),
    PointKind.END: Marker("EP", "end of the range", "line-ns-open", 10),
}
#: Marks that are not special points: the largest stable |psi| of a diagram or study, the current design.
LARGEST_PSI = Marker("max", "largest stable |psi|", "circle-open-dot", 14)
CURRENT_DESIGN = Marker("design", "current design", "line-ns", 16)
#: What the marks of the vocabulary are drawn with where nothing else says (a marker's outline).
OUTLINE = "#333"


def of(kind: str) -> Marker:
    """The marker of a kind of point (a kind outside the vocabulary is an error, not a default)."""
    return MARKERS[PointKind(kind)]


def marker(kind: str, colour: str, outline: str = OUTLINE, size: float | None = None) -> dict:
    """Plotly's ``marker`` of a point of ``kind`` in ``colour`` (the configuration's or the design's)."""
    m = of(kind)
    return {"symbol": m.symbol, "size": m.size if size is None else size, "color": colour,
            "line": {"width": 1.5 if m.symbol in ("x", "cross") else 1, "color": outline}}


def legend(fig, kinds, legend: str = "legend2", colour: str = "#555") -> None:
    """The legend entries of ``kinds`` (in the vocabulary's order), in grey: the marker means the kind."""
    present = {PointKind(k) for k in kinds}
    for kind, m in MARKERS.items():
        if kind in present:
            style.legend_key(fig, m.legend, legend, mode="markers", meta={"kind": m.label},
                             marker={"symbol": m.symbol, "size": m.size - 2, "color": colour,
                                     "line": {"width": 1, "color": OUTLINE}})


def symbols(figure: dict) -> dict[str, set[str]]:
    """The symbols a built figure (``fig.to_dict()``) draws, by the kind its traces name in ``meta``
    (a test reads every page's figures with it)."""
    out: dict[str, set[str]] = {}
    for trace in figure.get("data", []):
        meta = trace.get("meta")
        if isinstance(meta, dict) and "kind" in meta:
            out.setdefault(meta["kind"], set()).add(trace.get("marker", {}).get("symbol"))
    return out
