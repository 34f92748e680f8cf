"""The tables ``python -m shimmy`` prints (and the study's CSV) for this family's results, rendered from
their ``to_dict()``: a result read back from the shared cache reads exactly as one just computed.

Only definitions are imported here (no solver, no integrator), so that a cached answer is printed
without loading the numerics.
"""

from __future__ import annotations

import csv
from typing import Any
from urllib.parse import urlencode

from ...model.parameters import PARAMETER_SPECS
from ...model.units import KN, kn
from .design_space import FIGURES

#: Units the text shows in place of the JSON's SI unit: loads in kN, as everywhere else a person reads.
SHOWN = {"N": ("kN", 1.0 / KN)}


def shown(value: float | None, unit: str) -> tuple[float | None, str]:
    """(value, unit) as the text shows them: a load in N as kN; anything else as it is."""
    text_unit, factor = SHOWN.get(unit, (unit, 1.0))
    return (None if value is None else value * factor), text_unit

#: The columns of a study's rows after its parameters (``StudyResult.COLUMNS``).
STUDY_COLUMNS = ("config", "hopf_start", "hopf_end", "max_psi", "max_psi_V")


def sensitivity_summary(result: dict[str, Any], top: int = 8) -> str:
    """The tables ``python -m shimmy sensitivity`` prints, from ``SensitivityResult.to_dict()``: per quantity its
    ``top`` largest effects and the device parameters, then the parameters without effect with their reasons."""
    lines = [f"{result['config']} at Fz = {result['Fz'] / 1e3:g} kN: change of each quantity per +1 % of the "
             f"parameter (per half of its range in brackets); largest effects first, then the device parameters"]
    for q in result["quantities"]:
        value, unit = shown(q["value"], q["unit"])
        lines.append(f"\n{q['label']} = {value:.6g} {unit}")
        active = [r for r in q["rows"] if r["reason"] is None]
        for r in active[:top] + [r for r in active[top:] if r["device"]]:
            per_percent, per_half = shown(r["per_percent"], q["unit"])[0], shown(r["per_half_range"], q["unit"])[0]
            percent = "(value 0)" if per_percent is None else f"{per_percent:+.4g}"
            lines.append(f"  {r['name']:<12}{percent:>12} {unit:<4}({per_half:+.4g} {unit} per half range)")
        silent = [r["name"] for r in q["rows"] if r["reason"] is not None]
        if silent:
            lines.append(f"  no effect: {', '.join(silent)}")
    amplitude = result["max_psi"]
    if amplitude is not None and amplitude.get("dA_dp") is None:
        lines.append(f"\nlargest stable torsional amplitude: {amplitude['reason']}")
    reasons: dict[str, set[str]] = {}
    for by_name in result["no_effect"].values():
        for name, reason in by_name.items():
            reasons.setdefault(reason, set()).add(name)
    lines += [f"  {', '.join(sorted(n))}: {r}" for r, n in reasons.items()]
    return "\n".join(lines)


def constraint_text(constraint: dict[str, Any]) -> str:
    """A constraint of ``OptimisationResult.to_dict()`` as ``Constraint`` writes it: 'max_psi at 150 kN <= 0.02 rad'."""
    at = f" at {constraint['Fz'] / 1e3:g} kN" if constraint["Fz"] is not None else ""
    return f"{constraint['figure']}{at} {constraint['op']} {constraint['value']:g} {constraint['unit']}"


def optimise_summary(result: dict[str, Any]) -> str:
    """The lines ``python -m shimmy optimise`` prints, from ``OptimisationResult.to_dict()``: the problem, the
    optimum against the nominal design, the design, the constraints, the figures, the message and the
    workbench link."""
    f = result["objective_figure"]
    nominal = result["nominal_objective"]
    at = f" at {f['Fz'] / 1e3:g} kN" if f["Fz"] is not None else ""
    lines = [f"{result['config']}: {f['sense']} {f['label']}{at} over {', '.join(result['parameters'])} "
             f"({result['method']}, {result['evaluations']} evaluations, {result['elapsed_s']:.1f} s)",
             "  optimum {:.6g} {} (nominal ".format(*shown(result["objective"], f["unit"]))
             + ("not evaluated" if nominal is None else "{:.6g} {}".format(*shown(nominal, f["unit"]))) + ")",
             "  design: " + ", ".join(f"{n} = {v:.6g} {PARAMETER_SPECS[n].unit}".rstrip()
                                      for n, v in result["design"].items())]
    lines += [f"  constraint {constraint_text(c)}" for c in result["constraints"]]
    def figure(key: str, value: Any) -> str:  # "max_psi@150000 = 0.16 rad": the figure's unit, a load in kN
        spec = FIGURES.get(key.split("@")[0])
        if not isinstance(value, float) or spec is None:
            return f"{key}: {value}" if not isinstance(value, float) else f"{key} = {value:.6g}"
        return "{} = {:.6g} {}".format(key, *shown(value, spec.unit))

    for label, table in result["figures"].items():
        lines.append(f"  {label:<9}" + ", ".join(figure(k, v) for k, v in table.items()))
    lines.append(f"  {result['message']}")
    lines.append("  open in the workbench: /?" + urlencode(result["link_query"]))
    lines += [f"  warning: {w}" for w in result["warnings"]]
    return "\n".join(lines)


def robustness_summary(result: dict[str, Any]) -> str:
    """The table ``python -m shimmy robustness`` prints, from ``RobustnessResult.to_dict()``: the tolerances,
    each distribution's nominal value, mean, spread and percentiles, sampled and linear, and the
    probability of shimmy at the operating points; with a disturbance, that of shimmy and of each mode after it."""
    lines = [f"{result['config']} at Fz = {result['Fz'] / 1e3:g} kN, {result['samples']} samples "
             f"(seed {result['seed']}): "
             + ", ".join(f"{t['name']} {100 * t['relative']:g} % {t['distribution']}" for t in result["tolerances"]),
             f"  {'':<22}{'nominal':>10}{'mean':>10}{'std':>9}{'p05':>10}{'p95':>10}{'linear std':>12}"]
    rows = [(f"Hopf speed {k + 1} (m/s)", h, 1.0) for k, h in enumerate(result["hopf_points"])]
    if result["min_shimmy_Fz"]:
        rows.append(("min shimmy Fz (kN)", result["min_shimmy_Fz"], 1e-3))
    for label, h, k in rows:
        lines.append(f"  {label:<22}{h['nominal'] * k:>10.4g}{h['mean'] * k:>10.4g}{h['std'] * k:>9.3g}"
                     f"{h['p05'] * k:>10.4g}{h['p95'] * k:>10.4g}{h['linear_std'] * k:>12.3g}")
    sampled, linear = result["p_shimmy"], result["p_shimmy_linear"]
    lines.append("  P(shimmy) sampled / linear: " + ", ".join(f"{p} {sampled[p]:.3f}/{linear[p]:.3f}" for p in sampled))
    disturbed = result.get("p_shimmy_disturbed")
    if disturbed:
        d = result["disturbance"]
        lines.append(f"  after a disturbance up to {d['size']:g} {d['unit']} along {d['direction']} (every attractor "
                     "reached; 95 % intervals):")
        lines.append(f"    {'':<4}{'P(shimmy)':>22}{'P(torsional)':>24}{'P(lateral)':>24}{'linear':>9}")
        for p, share in disturbed.items():
            cells = [share, share["modes"]["torsional"], share["modes"]["lateral"]]
            lines.append(f"    {p:<4}" + "".join(f"{c['p']:>8.3f} [{c['ci95'][0]:.3f}, {c['ci95'][1]:.3f}]"
                                                   for c in cells) + f"{sampled[p]:>9.3f}")
    lines += [f"  warning: {w}" for w in result["warnings"]]
    return "\n".join(lines)


def study_summary(result: dict[str, Any]) -> str:
    """The table ``python -m shimmy study`` prints, from ``StudyResult.to_dict()``: one row per design and
    configuration."""
    parameters, v_range = result["parameters"], result["v_range"]
    lines = [f"study at Fz = {kn(result['Fz'])}, V {v_range[0]:g}..{v_range[1]:g} m/s "
             f"({result['elapsed_s']:.1f} s, {result['executor']})",
             "".join(f"{p:>12}" for p in parameters)
             + f"  {'config':<8}{'Hopf start':>11}{'Hopf end':>10}{'max psi':>10}{'at V':>8}"]

    def num(x, fmt):
        return "-" if x is None else format(x, fmt)

    for r in result["rows"]:
        lines.append("".join(f"{r[p]:>12.6g}" for p in parameters)
                     + f"  {r['config']:<8}{num(r['hopf_start'], '11.4f')}{num(r['hopf_end'], '10.4f')}"
                     f"{num(r['max_psi'], '10.5f')}{num(r['max_psi_V'], '8.2f')}")
    lines += study_curves_lines(result.get("curves", []))
    lines += [f"  warning: {w}" for w in result["warnings"]]
    return "\n".join(lines)


def study_curves_lines(curves: list[dict[str, Any]], rows: int = 11, columns: int = 4) -> list[str]:
    """The study curves as text: per configuration, p against each quantity on ``rows`` grid values
    (evenly picked, the ends included), at most ``columns`` curves side by side, and the special points."""
    lines: list[str] = []
    by_config: dict[tuple, list[dict[str, Any]]] = {}
    for c in curves:  # a table per configuration and grid (the curves on the same values of p side by side)
        key = (c["config"], tuple(c["p"]))
        while len(by_config.get(key, ())) == columns:
            key += (None,)
        by_config.setdefault(key, []).append(c)

    def num(x):
        return f"{'-':>14}" if x is None else f"{x:14.6g}"

    for (config, *_), group in by_config.items():
        p = group[0]["p"]
        lines.append(f"curves of {config} against {group[0]['param']} ({len(p)} exact points each, "
                     f"{p[0]:g}..{p[-1]:g}):")
        lines.append(f"{group[0]['param']:>14}"
                     + "".join(f"{_curve_name(c) + ' (' + shown(0.0, c['unit'])[1] + ')':>24}" for c in group))
        picks = sorted({round(k * (len(p) - 1) / (rows - 1)) for k in range(rows)}) if len(p) > 1 else [0]
        for i in picks:
            lines.append(f"{p[i]:14.6g}" + "".join(f"{num(shown(c['values'][i], c['unit'])[0]):>24}" for c in group))
        for c in group:
            for s in c["special_points"]:
                value, unit = shown(s.get("value"), c["unit"])
                lines.append(f"  {_curve_name(c)}: {s['kind']} at {c['param']} = {s['p']:.8g}"
                             + ("" if value is None else f", value {value:.8g} {unit}")
                             + (f" ({s['why']})" if s.get("why") else ""))
    return lines


def _curve_name(curve: dict[str, Any]) -> str:
    """A curve's quantity, with the number of the point it follows (GH and double-Hopf points)."""
    return curve["quantity"] + ("" if curve.get("point") is None else f" #{curve['point']}")


def write_study_csv(result: dict[str, Any], stream) -> None:
    """The rows of ``StudyResult.to_dict()`` as CSV to ``stream``: the parameters, the columns, the Hopf speeds."""
    w = csv.writer(stream)
    units = {"hopf_start": "hopf_start_m_s", "hopf_end": "hopf_end_m_s", "max_psi": "max_psi_rad",
             "max_psi_V": "max_psi_V_m_s"}
    parameters = result["parameters"]
    w.writerow(parameters + [units.get(c, c) for c in STUDY_COLUMNS] + ["hopf_points_m_s"])
    for r in result["rows"]:
        w.writerow([f"{r[p]:.10g}" for p in parameters]
                   + [r["config"]] + ["" if r[c] is None else f"{r[c]:.10g}" for c in STUDY_COLUMNS[1:]]
                   + [" ".join(f"{v:.10g}" for v in r["hopf_points"])])
