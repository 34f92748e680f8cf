"""Pages that follow the design: the design once it has stood still, and the previous answer kept
faint while the next is made.

The design store of a page follows a slider while it is dragged (the linear plots redraw on every
step); a computation of seconds follows the design only once it stands still: :func:`settled`
is a store that takes the design, in the browser (no server round trip), at once when it was
committed (a value typed and entered, a material chosen, the design reset) or a slider was let go
(the pointer released: at the release, however long the drag); after a change by the arrow keys,
which may be pressed again, :data:`SETTLE_MS` after the last one (a timer restarted by every
change). ``assets/input.js`` tells which: the pointer's state and the last input's kind.
:func:`fading` is what a page shows while the next answer is made: the previous figure under a
white veil, its title saying what is computed and for how long (a partial update of the figure:
nothing of it is sent again).
"""

from __future__ import annotations

from typing import Any

import dash
from dash import Input, Output, Patch, dcc

from . import ids, style

#: the quiet time after a change by the arrow keys before the design counts as standing still
SETTLE_MS = 600
#: over the previous figure while the next is made: its curves and regions stay, faint, for comparison
VEIL = {"type": "rect", "xref": "paper", "yref": "paper", "x0": 0, "x1": 1, "y0": 0, "y1": 1, "layer": "above",
        "fillcolor": "rgba(255,255,255,0.62)", "line": {"width": 0}}


def settled_id(page: Any) -> str:
    return f"{page}-design-settled"


def settled(page: Any) -> dcc.Store:
    """The store of ``page``'s design once it stood still, for the page's layout (its callback:
    :func:`follow_settled`, once at import)."""
    return dcc.Store(id=settled_id(page))


def follow_settled(page: Any) -> Input:
    """Register the browser's timer that fills :func:`settled` of ``page``; the Input to follow."""
    dash.clientside_callback(
        """
        function(design) {
            const C = window.dash_clientside, key = "shimmySettle_" + %s;
            window[key] = (window[key] || 0) + 1;
            const seq = window[key], input = window.shimmyInput || {last: null, onRelease: []};
            return new Promise(resolve => {
                const settle = () => resolve(seq === window[key] ? design : C.no_update);  // a later change: not this
                if (window.shimmyDesignCommitted || (input.last === "pointer" && !input.pointerDown)) {
                    settle();
                } else if (input.last === "pointer") {  // a slider held: at its release
                    input.onRelease.push(settle);
                } else {
                    setTimeout(settle, %d);
                }
            });
        }
        """ % (repr(str(page)), SETTLE_MS),
        Output(settled_id(page), "data"),
        Input(ids.design_store(page), "data"),
        prevent_initial_call=True,
    )
    return Input(settled_id(page), "data")


def fading(title: str, seconds: float) -> Patch:
    """The figure while the next answer is made: the shown one under :data:`VEIL`, titled ``title``
    and the seconds so far."""
    patch = Patch()
    patch["layout"]["shapes"] = [VEIL]
    # the whole title (the house style's), not its text alone: a placeholder figure has none
    patch["layout"]["title"] = style.title(f"{title}: {int(seconds)} s so far (faint: the previous one)")
    return patch
