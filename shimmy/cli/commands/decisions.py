"""Design decisions: ``sensitivity``, ``optimise``, ``robustness`` and the parametric ``study``."""

from __future__ import annotations

import sys

from ...model.parameters import FZ_RANGE, check_number
from ..common import (add_command, add_common, add_config, add_field, add_plane, add_progress, emit, float_list, names,
                      params, progress)


def _cmd_sensitivity(args) -> int:
    from ...analyses.decisions.sensitivity import sensitivity

    Fz = check_number("Fz", args.Fz, *FZ_RANGE, "N")
    result = sensitivity(args.config, Fz, params=params(args), names=names(args.params),
                         amplitude=not args.no_amplitude)
    emit(result.to_dict(), args.json, result.summary_text(top=args.top))
    return 0


def _cmd_optimise(args) -> int:
    from ...analyses.decisions.optimise import optimise

    Fz = check_number("Fz", args.Fz, *FZ_RANGE, "N")
    with progress(args) as bar:
        result = optimise(args.config, args.objective, parameters=names(args.params), Fz=Fz,
                          constraints=args.constraint or [], params=params(args), method=args.method,
                          starts=args.starts, local_runs=args.local_runs, seed=args.seed, progress=bar)
    emit(result.to_dict(), args.json, result.summary_text())
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
    emit(payload, args.json, result.summary_text())
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
    emit(result.to_dict(), args.json, result.summary_text())
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
