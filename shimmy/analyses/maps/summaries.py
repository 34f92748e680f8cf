"""The short table and the CSV file ``python -m shimmy map`` writes, rendered from the map's
``to_dict()`` (with its ``metrics``, as the service serves it): a map read back from the shared cache
reads exactly as one just computed.

Only definitions are imported here (no continuation, no integrator), so that a cached map is printed
without loading the numerics.
"""

from __future__ import annotations

import csv
from typing import Any

from ..core.response import ShimmyType


def map_summary(result: dict[str, Any]) -> str:
    """The short table ``python -m shimmy map`` prints, from ``StabilityMap.to_dict()`` and, under "metrics",
    :func:`~shimmy.analyses.maps.design_metrics.metrics` of that map: slices and grid, grid points by type,
    curves, the minimum shimmy load, the pure-torsion area (with metrics), the warnings."""
    shading = result["shading"]
    counts = {t: sum(row.count(t) for row in shading["types"]) for t in ShimmyType}
    v_range, fz_range = result["v_range"], result["fz_range"]
    lines = [f"{result['config']}: {len(result['Fz'])} classified slices, {len(shading['Fz'])} x {len(result['V'])} "
             f"grid, V {v_range[0]:g}..{v_range[1]:g} m/s, Fz {fz_range[0]:g}..{fz_range[1]:g} "
             f"N ({result['elapsed_s']:.1f} s, {result['executor']})",
             "  grid points by type: " + ", ".join(f"{t} {n}" for t, n in counts.items())
             + f"; {len(result['regions'])} region polygons",
             f"  Hopf curves {len(result['hopf_curves'])}, GH points {len(result['gh_points'])}, "
             f"fold curves {len(result['fold_curves'])}, torus curves {len(result['torus_curves'])}"]
    lowest = result["min_shimmy"]
    if lowest:
        lines.append(f"  minimum shimmy load {lowest['Fz']:.6g} N at V = {lowest['V']:.5g} m/s ({lowest['source']})")
    else:
        lines.append("  no shimmy anywhere in the map")
    metrics = result.get("metrics")
    if metrics is not None:
        lines.append(f"  pure-torsion area, Fz <= {metrics['band']['Fz'][1] / 1e3:g} kN: "
                     f"{metrics['torsion_area']:.6g} (m/s) kN")
    lines += [f"  warning: {w}" for w in result["warnings"]]
    return "\n".join(lines)


def write_map_csv(result: dict[str, Any], path) -> None:
    """The shading of ``StabilityMap.to_dict()`` (the map's answer on its fine grid), one row per (Fz, V), to
    the file ``path``."""
    shading = result["shading"]
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["Fz_N", "V_m_s", "shimmy_type"])
        for Fz, row in zip(shading["Fz"], shading["types"], strict=True):
            for V, t in zip(shading["V"], row, strict=True):
                w.writerow([f"{Fz:.10g}", f"{V:.10g}", t])
