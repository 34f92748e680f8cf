"""Design decisions: ``sensitivity``, ``optimise``, ``robustness`` and the parametric ``study``."""

from __future__ import annotations

import sys
from urllib.parse import urlencode

from ...model.parameters import FZ_RANGE, PARAMETER_SPECS, check_number
from ..common import (add_command, add_common, add_config, add_field, add_plane, add_progress, emit, float_list, names,
                      params, progress)


def _cmd_sensitivity(args) -> int:
    from ...analyses.decisions.sensitivity import sensitivity

    Fz = check_number("Fz", args.Fz, *FZ_RANGE, "N")
    result = sensitivity(args.config, Fz, params=params(args), names=names(args.params),
                         amplitude=not args.no_amplitude)
    payload = result.to_dict()
    lines = [f"{result.config.value} at Fz = {Fz / 1e3:g} kN: change of each quantity per +1 % of the parameter "
             f"(per half of its range in brackets); largest effects first, then the device parameters"]
    for q in payload["quantities"]:
        lines.append(f"\n{q['label']} = {q['value']:.6g} {q['unit']}")
        active = [r for r in q["rows"] if r["reason"] is None]
        shown = active[:args.top] + [r for r in active[args.top:] if r["device"]]
        for r in shown:
            percent = "(value 0)" if r["per_percent"] is None else f"{r['per_percent']:+.4g}"
            lines.append(f"  {r['name']:<12}{percent:>12} {q['unit']:<4}"
                         f"({r['per_half_range']:+.4g} {q['unit']} per half range)")
        silent = [r["name"] for r in q["rows"] if r["reason"] is not None]
        if silent:
            lines.append(f"  no effect: {', '.join(silent)}")
    if result.max_psi is not None and result.max_psi.get("dA_dp") is None:
        lines.append(f"\nlargest stable torsional amplitude: {result.max_psi['reason']}")
    reasons = {}
    for by_name in result.no_effect.values():
        for name, reason in by_name.items():
            reasons.setdefault(reason, set()).add(name)
    lines += [f"  {', '.join(sorted(n))}: {r}" for r, n in reasons.items()]
    emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_optimise(args) -> int:
    from ...analyses.decisions.optimise import FIGURES, optimise

    Fz = check_number("Fz", args.Fz, *FZ_RANGE, "N")
    with progress(args) as bar:
        result = optimise(args.config, args.objective, parameters=names(args.params), Fz=Fz,
                          constraints=args.constraint or [], params=params(args), method=args.method,
                          starts=args.starts, local_runs=args.local_runs, seed=args.seed, progress=bar)
    payload = result.to_dict()
    f = FIGURES[result.objective]
    lines = [f"{result.config.value}: {'maximise' if f.sense > 0 else 'minimise'} {f.label}"
             + (f" at {Fz / 1e3:g} kN" if f.at_load else "") + f" over {', '.join(result.names)} "
             f"({result.method}, {result.evaluations} evaluations, {result.elapsed_s:.1f} s)",
             f"  optimum {result.objective_value:.6g} {f.unit} (nominal "
             + ("not evaluated" if result.nominal_objective is None else f"{result.nominal_objective:.6g} {f.unit}")
             + ")",
             "  design: " + ", ".join(f"{n} = {v:.6g} {PARAMETER_SPECS[n].unit}".rstrip()
                                      for n, v in result.design.items())]
    for c in result.constraints:
        lines.append(f"  constraint {c}")
    for label, table in result.figures.items():
        lines.append(f"  {label:<9}" + ", ".join(f"{k} = {v:.6g}" if isinstance(v, float) else f"{k}: {v}"
                                                 for k, v in table.items()))
    lines.append(f"  {result.message}")
    lines.append("  open in the workbench: /?" + urlencode(result.link_query))
    lines += [f"  warning: {w}" for w in result.warnings]
    emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_robustness(args) -> int:
    from ...analyses.decisions.robustness import robustness

    Fz = check_number("Fz", args.Fz, *FZ_RANGE, "N")
    with progress(args) as bar:
        result = robustness(args.config, args.tolerance or [], samples=args.samples, Fz=Fz, params=params(args),
                            seed=args.seed, progress=bar)
    payload = result.to_dict()
    if not args.with_samples:
        for h in payload["hopf_points"] + ([payload["min_shimmy_Fz"]] if payload["min_shimmy_Fz"] else []):
            h.pop("samples")
    lines = [f"{result.config.value} at Fz = {Fz / 1e3:g} kN, {result.samples} samples (seed {result.seed}): "
             + ", ".join(f"{t.name} {100 * t.relative:g} % {t.distribution}" for t in result.tolerances),
             f"  {'':<22}{'nominal':>10}{'mean':>10}{'std':>9}{'p05':>10}{'p95':>10}{'linear std':>12}"]
    rows = [(f"Hopf speed {k + 1} (m/s)", h, 1.0) for k, h in enumerate(result.hopf_points)]
    if result.min_shimmy:
        rows.append(("min shimmy Fz (kN)", result.min_shimmy, 1e-3))
    for label, h, k in rows:
        lines.append(f"  {label:<22}{h['nominal'] * k:>10.4g}{h['mean'] * k:>10.4g}{h['std'] * k:>9.3g}"
                     f"{h['p05'] * k:>10.4g}{h['p95'] * k:>10.4g}{h['linear_std'] * k:>12.3g}")
    lines.append("  P(shimmy) sampled / linear: " + ", ".join(
        f"{p} {result.p_shimmy[p]:.3f}/{result.p_shimmy_linear[p]:.3f}" for p in result.p_shimmy))
    lines += [f"  warning: {w}" for w in result.warnings]
    emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_study(args) -> int:
    from ...analyses.decisions.studies import study, study_grid

    configs = [c.strip() for c in args.configs.split(",") if c.strip()]
    with progress(args) as bar:
        if args.param2:
            values = (float_list("values", args.values), float_list("values2", args.values2 or ""))
            result = study_grid((args.param, args.param2), values, configs=configs, Fz=args.Fz, params=params(args),
                                v_range=(args.v_min, args.v_max), progress=bar)
        else:
            result = study(args.param, float_list("values", args.values), configs=configs, Fz=args.Fz,
                           params=params(args), v_range=(args.v_min, args.v_max), progress=bar)
    if args.csv:
        result.write_csv(sys.stdout)
        return 0
    lines = [f"study at Fz = {result.Fz:g} N, V {result.v_range[0]:g}..{result.v_range[1]:g} m/s "
             f"({result.elapsed_s:.1f} s, {result.executor})",
             "".join(f"{p:>12}" for p in result.parameters)
             + f"  {'config':<8}{'Hopf start':>11}{'Hopf end':>10}{'max psi':>10}{'at V':>8}"]

    def num(x, fmt):
        return "-" if x is None else format(x, fmt)

    for r in result.rows:
        lines.append("".join(f"{r[p]:>12.6g}" for p in result.parameters)
                     + f"  {r['config']:<8}{num(r['hopf_start'], '11.4f')}{num(r['hopf_end'], '10.4f')}"
                     f"{num(r['max_psi'], '10.5f')}{num(r['max_psi_V'], '8.2f')}")
    lines += [f"  warning: {w}" for w in result.warnings]
    emit(result.to_dict(), args.json, "\n".join(lines))
    return 0


def add_parsers(commands) -> None:
    p = add_command(commands, "sensitivity", "derivatives of the Hopf speeds, the minimum shimmy load and the largest "
                                             "torsional amplitude with respect to every parameter", _cmd_sensitivity)
    add_config(p)
    add_field(p, "sensitivity", "--Fz", "vertical load (N)")
    p.add_argument("--params", help="comma-separated parameter names (default: all)")
    p.add_argument("--no-amplitude", action="store_true",
                   help="skip the largest torsional amplitude (which needs one bifurcation diagram)")
    p.add_argument("--top", type=int, default=8, help="rows per quantity in the table")
    add_common(p)

    p = add_command(commands, "optimise", "search device parameters for the best figure of merit under constraints",
                    _cmd_optimise)
    add_config(p)
    add_field(p, "optimise", "--objective", "maximise min_shimmy_Fz; minimise the shimmy interval width or max_psi at "
                                            "--Fz, or the pure-torsion area")
    add_field(p, "optimise", "--Fz", "load (N) of the figures at a load")
    p.add_argument("--params", help="comma-separated parameters to search in their ranges (default: the "
                                    "configuration's device parameters: r2,e_p,k_s,r3 with the NES, a_p,rho_p with "
                                    "the PD)")
    p.add_argument("--constraint", action="append", metavar="FIGURE[@Fz]<=VALUE",
                   help="constraint on a figure (repeatable), e.g. max_psi<=0.02 or min_shimmy_Fz>=80000")
    add_field(p, "optimise", "--method",
              "gradient: Sobol starts then SLSQP with analytic gradients; global: differential evolution")
    add_field(p, "optimise", "--starts", "start designs (gradient method)", type=int)
    add_field(p, "optimise", "--local-runs", "SLSQP runs from the best starts (gradient method)", type=int)
    add_field(p, "optimise", "--seed", "seed of the start designs", type=int)
    add_common(p)
    add_progress(p)

    p = add_command(commands, "robustness", "Hopf speeds, minimum shimmy load and shimmy at the operating points "
                                            "under parameter tolerances (quasi-Monte Carlo and linear propagation)",
                    _cmd_robustness)
    add_config(p)
    add_field(p, "robustness", "--Fz", "vertical load (N)")
    p.add_argument("--tolerance", action="append", metavar="NAME=REL[:normal|uniform]",
                   help="relative tolerance of a parameter (repeatable): standard deviation (normal, the default) "
                        "or half-width (uniform), e.g. k_lam=0.05")
    add_field(p, "robustness", "--samples", "quasi-Monte Carlo samples", type=int)
    add_field(p, "robustness", "--seed", "seed of the scrambled Sobol sequence", type=int)
    p.add_argument("--with-samples", action="store_true", help="include every sample's values in the JSON")
    add_common(p)
    add_progress(p)

    p = add_command(commands, "study", "parametric study: Hopf speeds and max amplitude against parameters", _cmd_study)
    p.add_argument("--param", required=True, help="parameter name (see 'params')")
    p.add_argument("--values", required=True, help="comma-separated values")
    p.add_argument("--param2", help="second parameter for a two-parameter grid")
    p.add_argument("--values2", help="comma-separated values of the second parameter")
    add_field(p, "study", "--configs", "comma-separated configurations")
    add_field(p, "study", "--Fz", "vertical load (N)")
    add_plane(p, "study", loads=False)
    p.add_argument("--csv", action="store_true", help="write the table as CSV to stdout")
    add_common(p)
    add_progress(p)
