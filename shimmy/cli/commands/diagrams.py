"""Diagrams: ``bifurcation`` (in V at one load), ``hopf-curves`` and ``curves`` (of cycles) in (V, Fz)."""

from __future__ import annotations

from ...analyses.diagrams.options import BifurcationOptions
from ...continuation.kinds import CYCLE_BIFURCATIONS as KINDS
from ...errors import InvalidParameterError
from ...model.parameters import check_number
from ..answers import OFF, Answer, add_no_cache, answer, design, numbers, request
from ..answers import emit as emit_answer
from ..common import (add_command, add_common, add_config, add_field, add_plane, add_progress, emit, float_list,
                      params, progress)


def _cmd_bifurcation(args) -> int:
    from ...analyses.diagrams.summaries import bifurcation_summary, write_bifurcation_csv

    canonical = request("bifurcation", {"config": args.config, **numbers("bifurcation", args, "Fz", "v_min", "v_max",
                                                                         "ntst"),
                                        "seeds": not args.no_seeds, "exact_nes": args.exact_nes,
                                        "params": design(args)})
    ds_max = check_number("ds_max", args.ds_max, 1e-3, 10.0)
    beyond = [flag for flag, given in (("--ds-max", ds_max != BifurcationOptions.ds_max),) if given]
    with progress(args) as bar:
        if beyond:  # options the API's request does not take: not the question it caches
            from ...analyses.diagrams.bifurcation import bifurcation

            options = BifurcationOptions(ntst=canonical["ntst"], ds=min(BifurcationOptions.ds, ds_max), ds_max=ds_max,
                                         exact_nes=canonical["exact_nes"], seeds=canonical["seeds"])
            result = bifurcation(args.config, canonical["Fz"], v_range=(canonical["v_min"], canonical["v_max"]),
                                 params=params(args), options=options, progress=bar)
            diagram = Answer(result.to_dict(), OFF, f"{' and '.join(beyond)}: not in the API's request")
        else:
            diagram = answer(args, "bifurcation", canonical, bar)
    if args.csv:
        write_bifurcation_csv(diagram.result, args.csv)
    emit_answer(diagram.result, [diagram], args.json, bifurcation_summary(diagram.result))
    return 0


def _cmd_hopf_curves(args) -> int:
    from ...analyses.diagrams.summaries import hopf_curves_summary

    canonical = request("hopf_curves", {"config": args.config,
                                        **numbers("hopf_curves", args, "v_min", "v_max", "fz_min", "fz_max"),
                                        "params": design(args)})
    with progress(args) as bar:
        curves = answer(args, "hopf_curves", canonical, bar)
    emit_answer(curves.result, [curves], args.json, hopf_curves_summary(curves.result))
    return 0


def _cmd_curves(args) -> int:
    from ...analyses.diagrams.cycle_curves import cycle_curves

    kinds = tuple(k.strip().upper() for k in str(args.kinds).split(",") if k.strip())
    for k in kinds:
        if k not in KINDS:
            raise InvalidParameterError("kinds", args.kinds, "comma-separated kinds among " + ", ".join(KINDS).lower(),
                                        f"names an unknown kind ({k.lower()})")
    loads = tuple(float_list("at_fz", args.at_fz)) if args.at_fz else ()
    with progress(args) as bar:
        result = cycle_curves(args.config, params=params(args), v_range=(args.v_min, args.v_max),
                              fz_range=(args.fz_min, args.fz_max), kinds=kinds, loads=loads, progress=bar)
    emit(result.to_dict(), args.json, result.summary_text())
    return 0


def add_parsers(commands) -> None:
    p = add_command(commands, "bifurcation", "bifurcation diagram in V: equilibrium and periodic branches",
                    _cmd_bifurcation)
    add_config(p)
    p.add_argument("--Fz", required=True, help="vertical load (N)")
    add_plane(p, "bifurcation", loads=False)
    add_field(p, "bifurcation", "--ntst", "collocation mesh intervals", limits=True)
    p.add_argument("--ds-max", default=BifurcationOptions.ds_max,
                   help="largest continuation step (scaled arclength); any other than the default is computed "
                        "without the cache (the API's request has no such field)")
    p.add_argument("--no-seeds", action="store_true", help="do not look for branches by simulation")
    p.add_argument("--exact-nes", action="store_true",
                   help="use the exact NES torque instead of the cubic (the cubic is within 1 %% of it only for "
                        "small NES rotations; a result beyond that range says so)")
    p.add_argument("--csv", metavar="FILE", help="write the branch points to FILE")
    add_common(p)
    add_progress(p)
    add_no_cache(p)

    p = add_command(commands, "hopf-curves", "Hopf curves of straight rolling in (V, Fz) with GH points",
                    _cmd_hopf_curves)
    add_config(p)
    add_plane(p, "hopf_curves")
    add_common(p)
    add_progress(p)
    add_no_cache(p)

    p = add_command(commands, "curves", "fold, torus and period-doubling curves of cycles in (V, Fz)", _cmd_curves)
    add_config(p)
    kinds = ",".join(KINDS).lower()
    p.add_argument("--kinds", default=kinds, help="comma-separated: " + kinds.replace(",", ", "))
    add_plane(p)
    p.add_argument("--at-fz", default="", help="loads (N, comma-separated) where each curve's crossings are located")
    add_common(p)
    add_progress(p)
