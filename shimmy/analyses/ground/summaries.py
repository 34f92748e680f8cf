"""Ground runs as ``python -m shimmy ground-run`` prints and writes them, from their ``to_dict()``: the
text of a run, the comparison of several runs of one profile against ``original``, the CSV of a
run's series. A run read back from the shared cache reads exactly as one just computed, and runs
from the cache compare as computed ones.

Only definitions are imported here (no integrator), so that cached runs are printed without loading
the numerics.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from ...version import __version__
from .kicks import outcome_text

#: The series of a run's ``to_dict()``, in the order of ``GroundRunResult.series()`` (the last three
#: only with the NES).
SERIES = ("t", "V", "Fz", "psi", "lateral", "envelope_psi", "envelope_lateral", "psis", "dpsis", "nes_relative")


def ratio(a: float, b: float) -> float | None:
    """a / b where both are finite and b > 0, else None."""
    return float(a / b) if b > 0 and math.isfinite(a) and math.isfinite(b) else None


def comparison_table(runs: Mapping[str, Mapping[str, Any]]) -> list[dict[str, Any]]:
    """One row per run (each ``GroundRunResult.summary()`` or ``to_dict()``, by configuration): time in
    shimmy, peaks, onset delay, speed range and, when ``original`` is among the runs, the change of the
    time in shimmy (s) and the ratios of the peaks to those of ``original``; with a kick, whether shimmy started
    after it, its mode and the outcome in words."""
    base = runs.get("original")
    rows = []
    for name, r in runs.items():
        row = {"config": name, "time_in_shimmy_s": r["time_in_shimmy_s"], "peak_psi": r["peak_psi"]["value"],
               "peak_lateral": r["peak_lateral"]["value"], "onset_delay_s": r["onset_delay_s"],
               "speed_range": r["speed_range"], "success": r["success"]}
        kick = r.get("kick")
        if kick is not None:  # what the kick started, if anything
            row.update(kick_shimmy_started=kick["shimmy_started"], kick_mode=kick["mode"],
                       kick_outcome=outcome_text(kick))
        if base is not None:
            row["time_in_shimmy_change_s"] = r["time_in_shimmy_s"] - base["time_in_shimmy_s"]
            row["peak_psi_ratio"] = ratio(r["peak_psi"]["value"], base["peak_psi"]["value"])
            row["peak_lateral_ratio"] = ratio(r["peak_lateral"]["value"], base["peak_lateral"]["value"])
        rows.append(row)
    return rows


def comparison_dict(profile: dict[str, Any], runs: dict[str, dict[str, Any]], elapsed_s: float) -> dict[str, Any]:
    """``GroundRunComparison.to_dict()`` of one profile's runs (each ``GroundRunResult.to_dict()``)."""
    return {"profile": profile, "comparison": comparison_table(runs), "elapsed_s": elapsed_s, "runs": runs,
            "version": __version__}


def ground_run_summary(run: dict[str, Any], header: bool = True) -> str:
    """The lines ``python -m shimmy ground-run`` prints for one run (``GroundRunResult.to_dict()``): time in
    shimmy, peaks, onset delay, boundary crossings, warnings; with ``header``, the profile and the
    thresholds first."""
    rows, o = run["profile"]["rows"], run["options"]
    speeds, loads = [r[1] for r in rows], [r[2] for r in rows]
    lines = [f"{run['profile']['name']} profile: {rows[-1][0] - rows[0][0]:g} s, "
             f"V {min(speeds):.4g}..{max(speeds):.4g} m/s, Fz {min(loads) / 1e3:.4g}..{max(loads) / 1e3:.4g} kN; "
             f"thresholds {o['psi_threshold']:g} rad, {1e3 * o['lateral_threshold']:g} mm"] if header else []
    span = run["speed_range"]
    speeds_text = "-" if span is None else f"{span[0]:.4g}..{span[1]:.4g} m/s"
    delay = "-" if run["onset_delay_s"] is None else f"{run['onset_delay_s']:.3g} s"
    psi, lateral = run["peak_psi"], run["peak_lateral"]
    lines.append(f"  {run['config']:<8} in shimmy {run['time_in_shimmy_s']:7.3f} s (V {speeds_text}); peak |psi| "
                 f"{psi['value']:.4g} rad at {psi['t']:.4g} s ({psi['V']:.4g} m/s); "
                 f"peak |l_g delta| {1e3 * lateral['value']:.4g} mm; onset delay {delay}")
    if run.get("kick") is not None:
        k = run["kick"]
        where = f"t = {k['t']:.4g} s, V = {k['V']:.4g} m/s"
        lines.append(f"      kick {k['kind']} {k['size']:+g} {k['unit']} at {where}: {outcome_text(k)}")
    for c in run["boundary_crossings"]:
        lines.append(f"      crosses the {c['curve']} curve at t = {c['t']:.4g} s, V = {c['V']:.5g} m/s, "
                     f"Fz = {c['Fz'] / 1e3:.5g} kN" + (f" ({c['direction']})" if "direction" in c else ""))
    if not run["success"]:
        lines.append(f"      {run['message']}")
    lines += [f"      warning: {w}" for w in run["warnings"]]
    return "\n".join(lines)


def comparison_summary(comparison: dict[str, Any]) -> str:
    """The profile and the thresholds, then each run's lines (:func:`ground_run_summary`), from
    ``GroundRunComparison.to_dict()``."""
    runs = list(comparison["runs"].values())
    return "\n".join([ground_run_summary(runs[0]), *(ground_run_summary(r, header=False) for r in runs[1:])])


def write_ground_run_csv(run: dict[str, Any], path) -> None:
    """The series of one run (``GroundRunResult.to_dict()`` with its series) to the CSV file ``path``."""
    names = [name for name in SERIES if name in run]
    data = np.column_stack([np.asarray(run[name], dtype=float) for name in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g")
