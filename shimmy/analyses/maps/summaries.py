"""The short table and the CSV file ``python -m shimmy map`` writes, rendered from the map's
``to_dict()`` (with its ``metrics``, as the service serves it): a map read back from the shared cache
reads exactly as one just computed.

Only definitions are imported here (no continuation, no integrator), so that a cached map is printed
without loading the numerics.
"""

from __future__ import annotations

import csv
from typing import Any

from ...model.units import kn, kn_range, mm
from ..core.response import ShimmyType


def map_summary(result: dict[str, Any]) -> str:
    """The short table ``python -m shimmy map`` prints, from ``StabilityMap.to_dict()`` and, under "metrics",
    :func:`~shimmy.analyses.maps.design_metrics.metrics` of that map: slices and grid, grid points by type,
    curves, the minimum shimmy load, the pure-torsion area (with metrics), the warnings. Types no grid point has are
    left out."""
    shading = result["shading"]
    counts = {t: sum(row.count(t) for row in shading["types"]) for t in ShimmyType}
    v_range, fz_range = result["v_range"], result["fz_range"]
    lines = [f"{result['config']}: {len(result['Fz'])} classified slices, {len(shading['Fz'])} x {len(result['V'])} "
             f"grid, V {v_range[0]:g}..{v_range[1]:g} m/s, Fz {kn_range(*fz_range)} "
             f"({result['elapsed_s']:.1f} s, {result['executor']})",
             "  grid points by type: " + ", ".join(f"{t} {n}" for t, n in counts.items() if n)
             + f"; {len(result['regions'])} region polygons",
             f"  Hopf curves {len(result['hopf_curves'])}, GH points {len(result['gh_points'])}, "
             f"fold curves {len(result['fold_curves'])}, torus curves {len(result['torus_curves'])}"]
    lowest = result["min_shimmy"]
    if lowest:
        lines.append(f"  minimum shimmy load {kn(lowest['Fz'])} at V = {lowest['V']:.5g} m/s ({lowest['source']})")
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


def _attractor_line(a: dict[str, Any]) -> str:
    amp = a["amplitude"]
    motion = "motion (simulated)" if a["kind"] == "simulation" else "cycle"
    what = "straight rolling" if a["mode"] == "equilibrium" else f"{a['mode']} {motion}"
    size = "" if a["mode"] == "equilibrium" else f"  psi {amp['psi']:.4g} rad, l_g delta {mm(amp['lateral'], 4)}"
    return f"  {what}{size}{'  (the standard start ends here)' if a['standard_start'] else ''}"


def _check_text(check: dict[str, Any] | None) -> str:
    if check is None:
        return ""
    sides = [f"{c['size']:.5g} {c['unit']} -> {c['mode']}" for c in (check["below"], check["above"]) if c is not None]
    return "; checked: " + ", ".join(sides) + (": confirmed" if check["confirmed"] else ": NOT confirmed")


def margins_summary(result: dict[str, Any]) -> str:
    """The lines ``python -m shimmy margins`` prints, from ``MarginsResult.to_dict()``: each attractor with the
    smallest disturbance that ends on it and its two check runs, the saddle cycles, the runs, the warnings."""
    direction = result["direction"]
    mix = result["options"].get("mix")
    along = {"energy": "over all directions (energy)", "mix": f"along the mix {mix}"}.get(direction,
                                                                                        f"along {direction}")
    origin = result.get("origin") or {"kind": "straight_rolling"}
    lines = [f"{result['config']} at V = {result['V']:g} m/s, Fz = {kn(result['Fz'])}: straight rolling "
             f"{'stable' if result['straight_rolling_stable'] else 'unstable'}, {len(result['attractors'])} "
             f"attractor{'s' if len(result['attractors']) != 1 else ''}; smallest disturbance {along}"]
    if origin["kind"] == "standard_attractor":
        lines.append(f"  from {origin['note']}")
    elif origin.get("note", "").startswith("the standard start"):
        lines.append(f"  from straight rolling: {origin['note']}")
    for a in result["attractors"]:
        lines.append(_attractor_line(a))
        m = a["min_disturbance"]
        if not m["reached"]:
            lines.append(f"      {m['note']}")
            continue
        if m["value"] == 0.0:
            text = f"0 (reached from the smallest size scanned, {m['upper']:.4g} {m['unit']})"
        else:
            text = f"{m['value']:.5g} {m['unit']} +- {m['tolerance']:.2g}"
        if direction in ("energy", "mix") and m["value"] > 0.0:
            parts = ", ".join(f"{k} {v:.4g}" for k, v in m["disturbance"].items())
            times = f"{m['factor']:.4g} times the mix, " if direction == "mix" else ""
            text += f" ({times}yaw angle of the same energy {m['equivalent_psi']:.4g} rad: {parts})"
        if "phase" in m and m["value"] > 0.0:
            text += f", at phase {m['phase']:.3g} of the period"
        lines.append(f"      smallest {'kick' if direction == 'mix' else direction}: {text}{_check_text(m['check'])}")
    for s in result["saddles"]:
        lines.append(f"  saddle cycle ({s['mode']}): psi {s['amplitude']['psi']:.4g} rad, "
                     f"l_g delta {mm(s['amplitude']['lateral'], 4)}")
    unsettled = result["unsettled_runs"]
    lines.append(f"  {result['runs']} runs in {result['elapsed_s']:.1f} s ({result['executor']})"
                 + (f"; {unsettled} of them settled on no attractor" if unsettled else ""))
    lines += [f"  warning: {w}" for w in result["warnings"]]
    return "\n".join(lines)


def basins_summary(result: dict[str, Any]) -> str:
    """The lines ``python -m shimmy basins`` prints, from ``BasinsResult.to_dict()``: each attractor with its
    share of the sampled disturbances and the 95 % interval, the runs that settled nowhere, the warnings."""
    o = result["options"]
    lines = [f"{result['config']} at V = {result['V']:g} m/s, Fz = {kn(result['Fz'])}: {o['samples']} disturbances "
             f"up to {o['radius']:g} rad of yaw or the same energy ({result['energy_J']:.4g} J), seed {o['seed']}"]
    for a in result["attractors"]:
        b = a["basin"]
        lines.append(_attractor_line(a))
        lines.append(f"      {b['count']} of {o['samples']}: {100 * b['fraction']:.1f} % "
                     f"(95 % interval {100 * b['ci95'][0]:.1f} to {100 * b['ci95'][1]:.1f} %)")
    if result["unsettled"] or result["failed"]:
        lines.append(f"  on none of them: {result['unsettled']} unsettled, {result['failed']} failed")
    lines.append(f"  {result['runs']} runs in {result['elapsed_s']:.1f} s ({result['executor']})")
    lines += [f"  warning: {w}" for w in result["warnings"]]
    return "\n".join(lines)


def _margin_cell(point: dict[str, Any] | None, max_size: float) -> str:
    if point is None:
        return "."
    if point["margin"] is None:
        return f">{max_size:g}" if point["worst"] is not None else "none"
    return ("0" if point["margin"] == 0.0 else f"{point['margin']:.3g}") + ("?" if point["confirmed"] is False else "")


def margin_map_summary(result: dict[str, Any]) -> str:
    """The lines ``python -m shimmy margin-map`` prints, from ``MarginMapResult.to_dict()``: the cells, how many
    hold two or more attractors, and the smallest yaw kick to torsional shimmy in each computed cell, as a table of
    speeds (rows) by loads (columns)."""
    c, o = result["counts"], result["options"]
    v_range, fz_range = result["v_range"], result["fz_range"]
    lines = [f"{result['config']}: disturbance margins on {result['grid']['n_v']} x {result['grid']['n_fz']} cells, "
             f"V {v_range[0]:g}..{v_range[1]:g} m/s, Fz {fz_range[0] / 1e3:g}..{fz_range[1] / 1e3:g} kN "
             f"({result['elapsed_s']:.1f} s, {result['executor']})",
             f"  {c['multistable']} cells with two or more attractors ({c['bistable']} Bistable); {c['computed']} "
             f"with a torsional cycle, computed: " + ", ".join(f"{t} {n}" for t, n in c["by_type"].items()),
             f"  worst shimmy: {result['worst']}",
             f"  min yaw kick from straight rolling to it (rad): 0 = the smallest kick scanned ({o['min_size']:g} rad) "
             f"already ends there, >{o['max_size']:g} = none up to {o['max_size']:g} rad, ? = not confirmed, . = one "
             "attractor or no torsional cycle"]
    points = {(p["Fz"], p["V"]): p for p in result["points"]}
    rows = [V for V in result["V"] if any((Fz, V) in points for Fz in result["Fz"])]
    if rows:
        corner = "V \\ Fz (kN)"
        lines.append("  " + f"{corner:>12}" + "".join(f"{Fz / 1e3:>8.4g}" for Fz in result["Fz"]))
        for V in rows:
            lines.append("  " + f"{V:>12.4g}" + "".join(f"{_margin_cell(points.get((Fz, V)), o['max_size']):>8}"
                                                         for Fz in result["Fz"]))
    smallest = result["smallest"]
    if smallest is not None:
        lines.append(f"  smallest margin above 0: {smallest['margin']:.4g} rad +- {smallest['tolerance']:.2g} at "
                     f"V = {smallest['V']:.4g} m/s, Fz = {smallest['Fz'] / 1e3:.4g} kN")
    lines.append(f"  {c['reached']} margins ({c['zero']} of them 0), {c['not_reached']} not reached, "
                 f"{c['unconfirmed']} not confirmed; {c['runs']} runs; each margin within {o['rtol']:g} of itself")
    lines += [f"  warning: {w}" for w in result["warnings"]]
    return "\n".join(lines)
