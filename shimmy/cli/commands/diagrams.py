"""Diagrams: ``bifurcation`` (in V at one load), ``hopf-curves`` and ``curves`` (of cycles) in (V, Fz)."""

from __future__ import annotations

import math

from ...analyses.diagrams.bifurcation import BifurcationOptions
from ...analyses.diagrams.cycle_curves import KINDS
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
    lines = [f"{result.config.value} at Fz = {result.Fz:g} N, V in [{result.v_min:g}, {result.v_max:g}] m/s "
             f"({result.elapsed_s:.2f} s)"]
    for h in result.hopf.hopf_points:
        lines.append(f"  H    V = {h.V:10.5f} m/s  {h.frequency_hz:.4f} Hz  {h.criticality.value}")
    for i, b in enumerate(result.branches[1:], start=1):
        stable = int(b.stable.sum())
        lines.append(f"  branch {i}: {b.kind} from {b.origin}; {b.V.size} points ({stable} stable), "
                     f"V {b.V.min():.4g}..{b.V.max():.4g} m/s, max |psi| {b.max_psi.max():.5g} rad; "
                     f"modes {', '.join(sorted({m for m in b.mode if m}))}")
        for s in b.special_points:
            if s["kind"] != "EP":
                lines.append(f"      {s['kind']:<4} V = {s['V']:.6g} m/s")
        lines.append(f"      ends: {b.stop_reason}")
    where = "" if result.max_psi_V is None else f" at V = {result.max_psi_V:.5g} m/s"
    lines.append(f"  max torsional amplitude of stable cycles: {result.max_psi:.6g} rad{where}")
    if result.mesh_check:
        lines.append(f"  mesh check: ntst {result.mesh_check['ntst']} -> {result.mesh_check['ntst_fine']} changes "
                     f"max |psi| by {result.mesh_check['change']:.2g} rad")
    lines += [f"  warning: {w}" for w in result.warnings]
    emit(result.to_dict(), args.json, "\n".join(lines))
    return 0


def _cmd_hopf_curves(args) -> int:
    from ...analyses.diagrams.hopf_curves import hopf_curves

    with progress(args) as bar:
        result = hopf_curves(args.config, params=params(args), v_range=(args.v_min, args.v_max),
                             fz_range=(args.fz_min, args.fz_max), progress=bar)
    lines = [f"{result.config.value}: {len(result.curves)} Hopf curve(s) in "
             f"V {result.v_range[0]:g}..{result.v_range[1]:g} m/s, "
             f"Fz {result.fz_range[0]:g}..{result.fz_range[1]:g} N ({result.elapsed_s:.2f} s)"]
    for i, c in enumerate(result.curves, start=1):
        lines.append(f"  curve {i}: {len(c.p)} points, V {c.p[:, 0].min():.4g}..{c.p[:, 0].max():.4g} m/s, "
                     f"Fz {c.p[:, 1].min():.5g}..{c.p[:, 1].max():.5g} N, {'closed' if c.closed else 'open'}")
        for g in c.gh_points:
            lines.append(f"      GH  V = {g['p'][0]:.6g} m/s, Fz = {g['p'][1]:.6g} N")
        for g in c.double_hopf:
            lines.append(f"      HH  V = {g['p'][0]:.6g} m/s, Fz = {g['p'][1]:.6g} N "
                         f"({g['omega'] / (2 * math.pi):.4g} and {g['omega2'] / (2 * math.pi):.4g} Hz)")
    if result.fz_minimum:
        lines.append(f"  lowest load on a Hopf curve: Fz = {result.fz_minimum['Fz']:.6g} N "
                     f"at V = {result.fz_minimum['V']:.6g} m/s")
    emit(result.to_dict(), args.json, "\n".join(lines))
    return 0


def _cmd_curves(args) -> int:
    from ...analyses.diagrams.cycle_curves import KEY_OF_KIND, cycle_curves

    kinds = tuple(k.strip().upper() for k in str(args.kinds).split(",") if k.strip())
    for k in kinds:
        if k not in KINDS:
            raise InvalidParameterError("kinds", args.kinds, "comma-separated kinds among " + ", ".join(KINDS).lower(),
                                        f"names an unknown kind ({k.lower()})")
    loads = tuple(float_list("at_fz", args.at_fz)) if args.at_fz else ()
    with progress(args) as bar:
        result = cycle_curves(args.config, params=params(args), v_range=(args.v_min, args.v_max),
                              fz_range=(args.fz_min, args.fz_max), kinds=kinds, loads=loads, progress=bar)
    data = result.to_dict()
    lines = [f"{result.config.value}: cycle-bifurcation curves in V {result.v_range[0]:g}..{result.v_range[1]:g} m/s, "
             f"Fz {result.fz_range[0]:g}..{result.fz_range[1]:g} N ({result.elapsed_s:.2f} s, "
             f"{result.starts_tried} curve starts)"]
    names = {"LPC": "fold", "NS": "torus", "PD": "period-doubling"}
    for kind in kinds:
        lines.append(f"  {names[kind]} curves: {len(data[KEY_OF_KIND[kind]])}")
    for i, c in enumerate(data["curves"], start=1):
        lines.append(f"  {i}. {names[c['kind']]} curve from {c['origin']}: {c['points']} points, Fz "
                     f"{c['fz_min']['Fz']:.6g} N (V {c['fz_min']['V']:.5g}) .. {c['fz_max']['Fz']:.6g} N "
                     f"(V {c['fz_max']['V']:.5g})")
        for x in c["crossings"]:
            lines.append(f"       at Fz = {x['Fz']:.6g} N: V = {x['V']:.6f} m/s, period {x['period']:.5g} s, "
                         f"max |psi| {x['max_psi']:.4g} rad")
        for e in c["stop_reasons"]:
            lines.append(f"       end: {e}")
    for p in data["codim2_points"]:
        lines.append(f"  {p['kind']:<5} V = {p['V']:.6g} m/s, Fz = {p['Fz']:.6g} N")
    for w in result.warnings:
        lines.append(f"  warning: {w}")
    emit(data, args.json, "\n".join(lines))
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
