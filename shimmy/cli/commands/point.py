"""One operating point: ``params``, ``hopf``, ``eigen``, ``simulate``."""

from __future__ import annotations

import math

from ...model.parameters import PARAMETER_SPECS
from ...model.units import kn
from ..answers import OFF, Answer, add_no_cache, answer, design, numbers, request
from ..answers import emit as emit_answer
from ..common import (EXIT_FAILED, add_command, add_common, add_config, add_field, add_operating_point, add_plane, emit,
                      params)


def _cmd_params(args) -> int:
    rows = [spec.to_dict() for spec in PARAMETER_SPECS.values()]
    lines = [f"{'name':<11}{'group':<6}{'unit':<11}{'default':>12}{'low':>11}{'high':>11}  description"]
    for s in PARAMETER_SPECS.values():
        lines.append(f"{s.name:<11}{s.group:<6}{s.unit:<11}{s.default:>12.6g}{s.low:>11.4g}{s.high:>11.4g}  "
                     f"{s.description}")
    emit({"parameters": rows}, args.json, "\n".join(lines))
    return 0


def _cmd_hopf(args) -> int:
    from ...analyses.core.summaries import hopf_summary

    hopf = answer(args, "hopf", request("hopf", {"config": args.config, **numbers("hopf", args, "Fz", "v_min", "v_max"),
                                                 "params": design(args)}))
    emit_answer(hopf.result, [hopf], args.json, hopf_summary(hopf.result))
    return 0


def _cmd_eigen(args) -> int:
    from ...analyses.core.stability import eigenvalues
    from ...model.parameters import check_operating_point

    V, Fz = check_operating_point(args.V, args.Fz)
    design = params(args)
    ev = eigenvalues(args.config, V, Fz, params=design)
    rows = [{"real": float(e.real), "imag": float(e.imag), "frequency_hz": float(abs(e.imag) / (2 * math.pi)),
             "damping_ratio": float(-e.real / abs(e)) if abs(e) > 0 else None} for e in ev]
    payload = {"config": args.config, "V": V, "Fz": Fz, "params": design.to_dict(), "eigenvalues": rows,
               "stable": bool(ev.real.max() < 0)}
    lines = [f"{args.config} at V = {V:g} m/s, Fz = {kn(Fz)}: x = 0 is "
             f"{'stable' if payload['stable'] else 'unstable'}",
             f"  {'real (1/s)':>14}{'imag (rad/s)':>16}{'f (Hz)':>10}{'zeta':>10}"]
    for r in rows:
        zeta = "-" if r["damping_ratio"] is None else f"{r['damping_ratio']:.4f}"
        lines.append(f"  {r['real']:>14.6g}{r['imag']:>16.6g}{r['frequency_hz']:>10.4f}{zeta:>10}")
    emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_simulate(args) -> int:
    from ...analyses.core.summaries import simulation_summary

    canonical = request("simulate", {"config": args.config,
                                     **numbers("simulate", args, "V", "Fz", "t_end", "psi0", "lateral0"),
                                     "exact_nes": args.exact_nes, "params": design(args)})
    if args.csv:  # the file needs the time series, which the cache does not hold
        from ...analyses.core.simulation import kicked_state, simulate
        from ...model.parameters import Parameters

        params = Parameters.from_dict(canonical["params"])
        result = simulate(args.config, canonical["V"], canonical["Fz"], t_end=canonical["t_end"], params=params,
                          exact_nes=canonical["exact_nes"],
                          x0=kicked_state(args.config, params, canonical["psi0"], canonical["lateral0"]))
        result.write_csv(args.csv)
        run = Answer(result.to_dict(), OFF, "--csv needs the time series, which the cache does not hold")
    else:
        run = answer(args, "simulate", canonical)
    payload = run.result
    emit_answer(payload, [run], args.json, simulation_summary(payload))
    return 0 if payload["success"] else EXIT_FAILED


def add_parsers(commands) -> None:
    p = add_command(commands, "params", "list every parameter with unit, default, range", _cmd_params)
    add_common(p, design=False)

    p = add_command(commands, "hopf", "Hopf points of straight rolling in V at one load", _cmd_hopf)
    add_config(p)
    p.add_argument("--Fz", required=True, help="vertical load (N)")
    add_plane(p, "hopf", loads=False)
    add_common(p)
    add_no_cache(p)

    p = add_command(commands, "eigen", "eigenvalues of straight rolling at one operating point", _cmd_eigen)
    add_operating_point(p)

    p = add_command(commands, "simulate", "time history at one operating point", _cmd_simulate)
    add_operating_point(p)
    add_field(p, "simulate", "--t-end", "simulated time (s)", limits=True)
    add_field(p, "simulate", "--psi0", "initial torsion psi (rad; the rest of the state at rest)", limits=True)
    add_field(p, "simulate", "--lateral0", "initial lateral bending displacement l_g delta (m)", limits=True)
    p.add_argument("--exact-nes", action="store_true", help="use the exact NES torque instead of the cubic")
    p.add_argument("--csv", metavar="FILE", help="write the time series to FILE (computed: the cache holds no series)")
    add_no_cache(p)
