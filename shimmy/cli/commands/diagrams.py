"""Diagrams: ``bifurcation`` (in V at one load), ``hopf-curves`` and ``curves`` (of cycles) in (V, Fz)."""

from __future__ import annotations

from ...analyses.diagrams.options import BifurcationOptions
from ...continuation.kinds import CYCLE_BIFURCATIONS as KINDS
from ...errors import InvalidParameterError
from ...model.parameters import check_number
from ..common import (add_command, add_common, add_config, add_field, add_plane, add_progress, emit, float_list, limit,
                      params, progress)


def _cmd_bifurcation(args) -> int:
    from ...analyses.diagrams.bifurcation import bifurcation

    ntst = limit("bifurcation", "ntst", args.ntst)
    ds_max = check_number("ds_max", args.ds_max, 1e-3, 10.0)
    options = BifurcationOptions(ntst=ntst, ds=min(BifurcationOptions.ds, ds_max), ds_max=ds_max,
                                 exact_nes=args.exact_nes, seeds=not args.no_seeds)
    with progress(args) as bar:
        result = bifurcation(args.config, args.Fz, v_range=(args.v_min, args.v_max), params=params(args),
                             options=options, progress=bar)
    if args.csv:
        result.write_csv(args.csv)
    emit(result.to_dict(), args.json, result.summary_text())
    return 0


def _cmd_hopf_curves(args) -> int:
    from ...analyses.diagrams.hopf_curves import hopf_curves

    with progress(args) as bar:
        result = hopf_curves(args.config, params=params(args), v_range=(args.v_min, args.v_max),
                             fz_range=(args.fz_min, args.fz_max), progress=bar)
    emit(result.to_dict(), args.json, result.summary_text())
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
    p.add_argument("--ds-max", default=BifurcationOptions.ds_max, help="largest continuation step (scaled arclength)")
    p.add_argument("--no-seeds", action="store_true", help="do not look for branches by simulation")
    p.add_argument("--exact-nes", action="store_true", help="use the exact NES torque instead of the cubic")
    p.add_argument("--csv", metavar="FILE", help="write the branch points to FILE")
    add_common(p)
    add_progress(p)

    p = add_command(commands, "hopf-curves", "Hopf curves of straight rolling in (V, Fz) with GH points",
                    _cmd_hopf_curves)
    add_config(p)
    add_plane(p, "hopf_curves")
    add_common(p)
    add_progress(p)

    p = add_command(commands, "curves", "fold, torus and period-doubling curves of cycles in (V, Fz)", _cmd_curves)
    add_config(p)
    kinds = ",".join(KINDS).lower()
    p.add_argument("--kinds", default=kinds, help="comma-separated: " + kinds.replace(",", ", "))
    add_plane(p)
    p.add_argument("--at-fz", default="", help="loads (N, comma-separated) where each curve's crossings are located")
    add_common(p)
    add_progress(p)
