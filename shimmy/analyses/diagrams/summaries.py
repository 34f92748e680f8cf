"""The short tables and CSV files ``python -m shimmy`` writes for this family's results, rendered from
their ``to_dict()``: a result read back from the shared cache reads exactly as one just computed.

Only definitions are imported here (no continuation, no integrator), so that a cached answer is
printed without loading the numerics.
"""

from __future__ import annotations

import csv
from typing import Any

from ...continuation.kinds import PointKind
from ...model.units import kn, kn_range


def bifurcation_summary(result: dict[str, Any]) -> str:
    """The short table ``python -m shimmy bifurcation`` prints, from ``BifurcationResult.to_dict()``: the Hopf
    points, each periodic branch with its special points and end, the largest stable amplitude, the mesh
    check, the warnings."""
    lines = [f"{result['config']} at Fz = {kn(result['Fz'])}, V in [{result['v_min']:g}, {result['v_max']:g}] m/s "
             f"({result['elapsed_s']:.2f} s)"]
    for h in result["hopf_points"]:
        lines.append(f"  H    V = {h['V']:10.5f} m/s  {h['frequency_hz']:.4f} Hz  {h['criticality']}")
    for i, b in enumerate(result["branches"][1:], start=1):
        points = b["points"]
        speeds = [p["V"] for p in points]
        stable = sum(1 for p in points if p["stable"])
        lines.append(f"  branch {i}: {b['kind']} from {b['origin']}; {len(points)} points ({stable} stable), "
                     f"V {min(speeds):.4g}..{max(speeds):.4g} m/s, max |psi| "
                     f"{max(p['max_psi'] for p in points):.5g} rad; "
                     f"modes {', '.join(sorted({p['mode'] for p in points if p['mode']}))}")
        for s in b["special_points"]:
            if s["kind"] != PointKind.END:
                lines.append(f"      {s['kind']:<4} V = {s['V']:.6g} m/s")
        lines.append(f"      ends: {b['stop_reason']}")
    where = "" if result["max_psi_V"] is None else f" at V = {result['max_psi_V']:.5g} m/s"
    lines.append(f"  max torsional amplitude of stable cycles: {result['max_psi']:.6g} rad{where}")
    check = result["mesh_check"]
    if check:
        lines.append(f"  mesh check: ntst {check['ntst']} -> {check['ntst_fine']} changes "
                     f"max |psi| by {check['change']:.2g} rad")
    lines += [f"  warning: {w}" for w in result["warnings"]]
    return "\n".join(lines)


def write_bifurcation_csv(result: dict[str, Any], path) -> None:
    """Every point of every branch of ``BifurcationResult.to_dict()``, one row each, to the file ``path``."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["branch", "kind", "V_m_s", "period_s", "max_psi_rad", "max_lateral_m", "stable", "mode"])
        for i, b in enumerate(result["branches"]):
            for p in b["points"]:
                w.writerow([i, b["kind"], f"{p['V']:.10g}", "" if p["period"] is None else f"{p['period']:.10g}",
                            f"{p['max_psi']:.10g}", f"{p['max_lateral']:.10g}", int(bool(p["stable"])),
                            p["mode"] or ""])


def hopf_curves_summary(result: dict[str, Any]) -> str:
    """The short table ``python -m shimmy hopf-curves`` prints, from ``HopfCurvesResult.to_dict()``: each curve
    with its GH and double-Hopf points, and the lowest load on a curve."""
    v_range, fz_range = result["v_range"], result["fz_range"]
    lines = [f"{result['config']}: {len(result['curves'])} Hopf curve(s) in V {v_range[0]:g}..{v_range[1]:g} m/s, "
             f"Fz {kn_range(*fz_range)} ({result['elapsed_s']:.2f} s)"]
    for i, c in enumerate(result["curves"], start=1):
        speeds, loads = [p["V"] for p in c["points"]], [p["Fz"] for p in c["points"]]
        lines.append(f"  curve {i}: {len(c['points'])} points, V {min(speeds):.4g}..{max(speeds):.4g} m/s, "
                     f"Fz {kn_range(min(loads), max(loads), 5)}, {'closed' if c['closed'] else 'open'}")
        for g in c["gh_points"]:
            lines.append(f"      GH  V = {g['V']:.6g} m/s, Fz = {kn(g['Fz'])}")
        for g in c["double_hopf_points"]:
            lines.append(f"      HH  V = {g['V']:.6g} m/s, Fz = {kn(g['Fz'])} "
                         f"({g['frequency_hz']:.4g} and {g['frequency2_hz']:.4g} Hz)")
    lowest = result["fz_minimum"]
    if lowest:
        lines.append(f"  lowest load on a Hopf curve: Fz = {kn(lowest['Fz'])} at V = {lowest['V']:.6g} m/s")
    return "\n".join(lines)
