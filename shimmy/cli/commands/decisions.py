"""Design decisions: ``sensitivity``, ``optimise``, ``robustness`` and the parametric ``study``."""

from __future__ import annotations

import sys

from ..answers import add_no_cache, answer, design, emit, note, numbers, request
from ..common import (add_command, add_common, add_config, add_field, add_plane, add_progress, float_list, names,
                      progress)


def _cmd_sensitivity(args) -> int:
    from ...analyses.decisions.summaries import sensitivity_summary

    derivatives = answer(args, "sensitivity", request("sensitivity", {
        "config": args.config, **numbers("sensitivity", args, "Fz"), "names": names(args.params),
        "amplitude": not args.no_amplitude, "params": design(args)}))
    emit(derivatives.result, [derivatives], args.json, sensitivity_summary(derivatives.result, top=args.top))
    return 0


def _cmd_optimise(args) -> int:
    from ...analyses.decisions.summaries import optimise_summary

    canonical = request("optimise", {
        "config": args.config, "objective": args.objective, "parameters": names(args.params),
        **numbers("optimise", args, "Fz"), "constraints": args.constraint or [], "method": args.method,
        "starts": args.starts, "local_runs": args.local_runs, "seed": args.seed, "params": design(args)})
    with progress(args) as bar:
        optimum = answer(args, "optimise", canonical, bar)
    emit(optimum.result, [optimum], args.json, optimise_summary(optimum.result))
    return 0


def _cmd_robustness(args) -> int:
    from ...analyses.decisions.summaries import robustness_summary

    disturbance = {} if args.disturbance is None else numbers("robustness", args, "disturbance")
    canonical = request("robustness", {"config": args.config, "tolerances": args.tolerance or [],
                                       "samples": args.samples, **numbers("robustness", args, "Fz"), "seed": args.seed,
                                       **disturbance, "disturbance_direction": args.disturbance_direction,
                                       "params": design(args)})
    with progress(args) as bar:
        spread = answer(args, "robustness", canonical, bar)
    payload = spread.result
    if not args.with_samples:
        payload = {**payload, "hopf_points": [_without_samples(h) for h in payload["hopf_points"]],
                   "min_shimmy_Fz": payload["min_shimmy_Fz"] and _without_samples(payload["min_shimmy_Fz"])}
    emit(payload, [spread], args.json, robustness_summary(payload))
    return 0


def _without_samples(distribution: dict) -> dict:
    return {k: v for k, v in distribution.items() if k != "samples"}


def _cmd_study(args) -> int:
    from ...analyses.decisions.summaries import study_summary, write_study_csv

    canonical = request("study", {
        "parameter": args.param, "values": float_list("values", args.values), "parameter2": args.param2,
        "values2": None if args.values2 is None else float_list("values2", args.values2),
        "configs": [c.strip() for c in args.configs.split(",") if c.strip()],
        **numbers("study", args, "Fz", "v_min", "v_max"), "params": design(args)})
    with progress(args) as bar:
        rows = answer(args, "study", canonical, bar)
    if args.csv:
        write_study_csv(rows.result, sys.stdout)
        note([rows])
        return 0
    emit(rows.result, [rows], args.json, study_summary(rows.result))
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
    add_no_cache(p)

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
    add_no_cache(p)

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
    add_field(p, "robustness", "--disturbance", "also P(shimmy) after a disturbance up to this size from straight "
              "rolling, counting every attractor it reaches, and which mode (rad, as the yaw angle of the same energy; "
              "about 5 s per sample and core)", limits=True)
    add_field(p, "robustness", "--disturbance-direction", "the disturbed component, or energy (all four)")
    p.add_argument("--with-samples", action="store_true", help="include every sample's values in the JSON")
    add_common(p)
    add_progress(p)
    add_no_cache(p)

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
    add_no_cache(p)
