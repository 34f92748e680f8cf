"""Command line: ``python -m shimmy COMMAND ...`` (``python -m shimmy --help`` lists the commands).

Results go to stdout (JSON with ``--json``, a short table otherwise). Bad input exits
with status 2 and a message on stderr naming the field, its value and what is allowed.
The limits of every option that the API also takes (t_end, resolution, ntst, ...) are the
API's, read from its request schemas. Long commands report progress on stderr: a bar on a
terminal, plain lines otherwise (``--progress``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any, Sequence
from urllib.parse import urlencode

import numpy as np

from .model.configurations import Configuration
from .continuation.errors import InvalidInputError
from .errors import EXPECTED_ERRORS, GeometryError, InvalidParameterError
from .model.parameters import (DEFAULT_MAP_SLICES, FZ_RANGE, MATERIALS, PARAMETER_SPECS, V_RANGE, Parameters,
                               check_number)
from .service import schemas

EXIT_BAD_INPUT = 2
EXIT_FAILED = 1


def _limit(analysis: str, name: str, value: Any) -> float | int:
    """``value`` checked against the limits the API gives field ``name`` of ``analysis`` (one definition)."""
    f = schemas.SCHEMAS[analysis].field(name)
    number = check_number(name, value, f.low, f.high, f.unit, f.kind == "integer")
    return int(number) if f.kind == "integer" else number


def _parse_sets(items: Sequence[str] | None) -> dict[str, str]:
    overrides: dict[str, str] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise InvalidParameterError("--set", item, "NAME=VALUE with NAME from 'python -m shimmy params'",
                                        "is not of the form NAME=VALUE")
        overrides[name.strip()] = value.strip()
    return overrides


def _params(args) -> Parameters:
    params = Parameters()
    if getattr(args, "material", None):
        params = params.with_material(args.material)
    return params.with_overrides(_parse_sets(args.set))


def _emit(payload: dict[str, Any], as_json: bool, text: str) -> None:
    if as_json:
        json.dump(payload, sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(text)


def _cmd_params(args) -> int:
    rows = [spec.to_dict() for spec in PARAMETER_SPECS.values()]
    lines = [f"{'name':<11}{'group':<6}{'unit':<11}{'default':>12}{'low':>11}{'high':>11}  description"]
    for s in PARAMETER_SPECS.values():
        lines.append(f"{s.name:<11}{s.group:<6}{s.unit:<11}{s.default:>12.6g}{s.low:>11.4g}{s.high:>11.4g}  "
                     f"{s.description}")
    _emit({"parameters": rows}, args.json, "\n".join(lines))
    return 0


def _cmd_hopf(args) -> int:
    from .analyses.core.stability import hopf_points

    result = hopf_points(args.config, args.Fz, params=_params(args), v_range=(args.v_min, args.v_max))
    payload = result.to_dict()
    lines = [f"{result.config.value} at Fz = {result.Fz:g} N, V in [{result.v_min:g}, {result.v_max:g}] m/s"]
    if not result.hopf_points:
        lines.append("  no Hopf point")
    for h in result.hopf_points:
        lines.append(f"  Hopf V = {h.V:.6f} m/s  f = {h.frequency_hz:.4f} Hz  {h.criticality.value}"
                     f"  ({'loses' if h.destabilising else 'regains'} stability as V increases)")
    for iv in result.unstable_intervals:
        lines.append(f"  x = 0 unstable for V in [{iv[0]:.6g}, {iv[1]:.6g}] m/s")
    _emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_eigen(args) -> int:
    from .model.parameters import check_operating_point
    from .analyses.core.stability import eigenvalues

    V, Fz = check_operating_point(args.V, args.Fz)
    params = _params(args)
    ev = eigenvalues(args.config, V, Fz, params=params)
    rows = [{"real": float(e.real), "imag": float(e.imag), "frequency_hz": float(abs(e.imag) / (2 * math.pi)),
             "damping_ratio": float(-e.real / abs(e)) if abs(e) > 0 else None} for e in ev]
    payload = {"config": args.config, "V": V, "Fz": Fz, "params": params.to_dict(), "eigenvalues": rows,
               "stable": bool(ev.real.max() < 0)}
    lines = [f"{args.config} at V = {V:g} m/s, Fz = {Fz:g} N: x = 0 is "
             f"{'stable' if payload['stable'] else 'unstable'}",
             f"  {'real (1/s)':>14}{'imag (rad/s)':>16}{'f (Hz)':>10}{'zeta':>10}"]
    for r in rows:
        zeta = "-" if r["damping_ratio"] is None else f"{r['damping_ratio']:.4f}"
        lines.append(f"  {r['real']:>14.6g}{r['imag']:>16.6g}{r['frequency_hz']:>10.4f}{zeta:>10}")
    _emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_simulate(args) -> int:
    from .analyses.core.simulation import simulate

    result = simulate(args.config, args.V, args.Fz, params=_params(args),
                      t_end=_limit("simulate", "t_end", args.t_end), exact_nes=args.exact_nes)
    if args.csv:
        result.write_csv(args.csv)
    payload = result.to_dict()
    amp = result.amplitude
    freq = "-" if result.frequency_hz != result.frequency_hz else f"{result.frequency_hz:.4f} Hz"
    text = (f"{result.config.value} at V = {result.V:g} m/s, Fz = {result.Fz:g} N, {result.options.t_end:g} s\n"
            f"  response        {result.response_type.value}{'' if result.steady else ' (not yet steady)'}\n"
            f"  max |psi|       {amp['psi']:.6g} rad\n"
            f"  max |l_g delta| {amp['lateral']:.6g} m\n"
            f"  frequency       {freq}\n"
            f"  {result.message}")
    _emit(payload, args.json, text)
    return 0 if result.success else EXIT_FAILED


def _read_profile_csv(path: str) -> tuple[list[list[Any]], list[int]]:
    """Rows [t, V, Fz] of a CSV file (an optional header naming the columns t, V, Fz in any order;
    blank lines and lines starting with # skipped) and the file line of each row."""
    import csv

    with open(path, newline="") as f:
        lines = [(k, row) for k, row in enumerate(csv.reader(f), start=1)
                 if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    order = [0, 1, 2]
    if lines:
        head = [c.strip() for c in lines[0][1]]
        try:
            [float(c) for c in head]
        except ValueError:
            if sorted(head) != sorted(["t", "V", "Fz"]):
                raise InvalidParameterError(f"{path}: header", ",".join(head), "the columns t, V, Fz (s, m/s, N)",
                                            "does not name the columns") from None
            order = [head.index(c) for c in ("t", "V", "Fz")]
            lines = lines[1:]

    def cell(text: str) -> Any:
        try:
            return float(text)
        except ValueError:
            return text.strip()  # refused by name and row

    rows = [[cell(row[i]) for i in order] if len(row) == 3 else [cell(c) for c in row] for _, row in lines]
    return rows, [k for k, _ in lines]


def _profile(args):
    from .analyses.ground.ground_profiles import PRESETS, preset, profile_from_table

    settings = _parse_sets(args.profile_set)
    if args.profile in PRESETS:
        return preset(args.profile, {k: v for k, v in settings.items()})
    if settings:
        raise InvalidParameterError("--profile-set", args.profile_set, f"only with a preset ({', '.join(PRESETS)})",
                                    "is given with a table")
    rows, lines = _read_profile_csv(args.profile)
    try:
        return profile_from_table(rows)
    except InvalidParameterError as exc:  # name the file's line as well
        if exc.field.startswith("profile["):
            row = int(exc.field[len("profile["):].split("]")[0])
            raise InvalidParameterError(exc.field, exc.value, exc.allowed,
                                        message=f"{args.profile}, line {lines[row]}: {exc}") from None
        raise


def _cmd_ground_run(args) -> int:
    from .analyses.ground.ground_run import GroundRunOptions, ground_runs
    from .model.parameters import check_number

    profile = _profile(args)
    options = GroundRunOptions(psi_threshold=args.psi_threshold, lateral_threshold=args.lateral_threshold,
                               exact_nes=args.exact_nes, cycle_curves=args.fold_torus)
    series_dt = check_number("series_dt", args.series_dt, options.dt_out, 1.0, "s")
    stride = max(1, int(round(series_dt / options.dt_out)))
    configs = [c.value for c in Configuration] if args.config == "all" else [args.config]
    comparison = ground_runs(profile, params=_params(args), configs=configs, options=options)
    runs = comparison.runs
    if len(runs) == 1:
        (result,) = runs.values()
        if args.csv:
            names = list(result.series())
            data = np.column_stack([np.asarray(v) for v in result.series(stride).values()])
            np.savetxt(args.csv, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g")
        payload = result.to_dict(stride)
    else:
        payload = comparison.to_dict(stride)
    lines = [f"{profile.name} profile: {profile.duration:g} s, V {profile.V.min():.4g}..{profile.V.max():.4g} m/s, "
             f"Fz {profile.Fz.min() / 1e3:.4g}..{profile.Fz.max() / 1e3:.4g} kN; thresholds "
             f"{options.psi_threshold:g} rad, {1e3 * options.lateral_threshold:g} mm"]
    for name, r in runs.items():
        speeds = "-" if r.speed_range is None else f"{r.speed_range[0]:.4g}..{r.speed_range[1]:.4g} m/s"
        delay = "-" if r.onset_delay_s is None else f"{r.onset_delay_s:.3g} s"
        lines.append(f"  {name:<8} in shimmy {r.time_in_shimmy_s:7.3f} s (V {speeds}); peak |psi| "
                     f"{r.peak_psi['value']:.4g} rad at {r.peak_psi['t']:.4g} s ({r.peak_psi['V']:.4g} m/s); "
                     f"peak |l_g delta| {1e3 * r.peak_lateral['value']:.4g} mm; onset delay {delay}")
        for c in r.boundary_crossings:
            lines.append(f"      crosses the {c['curve']} curve at t = {c['t']:.4g} s, V = {c['V']:.5g} m/s, "
                         f"Fz = {c['Fz'] / 1e3:.5g} kN" + (f" ({c['direction']})" if "direction" in c else ""))
        if not r.success:
            lines.append(f"      {r.message}")
        lines += [f"      warning: {w}" for w in r.warnings]
    _emit(payload, args.json, "\n".join(lines))
    return 0 if all(r.success for r in runs.values()) else EXIT_FAILED


def _cmd_devices(args) -> int:
    from .analyses.core.device_curves import nes_curve, pd_curves

    params = _params(args)
    nes_c = nes_curve(params=params)
    pds = pd_curves(params=params, v_max=_limit("devices", "v_max", args.v_max))
    payload = {"params": params.to_dict(), "nes": nes_c.to_dict(), "pd": [c.to_dict() for c in pds]}
    err = nes_c.cubic_error_at
    lines = [f"NES: k1 = {nes_c.k1:.6g} N m/rad, k3 = {nes_c.k3:.6g} N m/rad^3; cubic vs exact torque: "
             + ", ".join(f"{100 * e:.2f} % for |a| <= {a} rad" for a, e in err.items()),
             "PD torsional damping c_eq (N m s/rad) at tangential speed v (m/s):",
             "  " + f"{'v':>8}" + "".join(f"{c.material:>12}" for c in pds)]
    for i in np.linspace(0, pds[0].speed.size - 1, 6).astype(int):
        lines.append("  " + f"{pds[0].speed[i]:>8.3g}" + "".join(f"{c.torsional_damping[i]:>12.5g}" for c in pds))
    _emit(payload, args.json, "\n".join(lines))
    return 0


class _ProgressBar:
    """Progress on stderr: a one-line bar on a terminal, plain log lines anywhere else (a script, a
    notebook, a CI log), or nothing. ``mode``: "auto" (bar on a terminal, lines otherwise), "bar",
    "log" or "none". Lines are written when the message changes or the fraction moves by 5 %."""

    def __init__(self, stream=None, width: int = 30, mode: str = "auto"):
        self.stream = stream or sys.stderr
        self.width = width
        if mode == "auto":
            mode = "bar" if self.stream.isatty() else "log"
        self.mode = mode
        self.enabled = mode == "bar"
        self._last: tuple[float, str] | None = None

    def __call__(self, fraction: float, message: str) -> None:
        fraction = min(max(fraction, 0.0), 1.0)
        if self.mode == "log":
            if self._last is None or message != self._last[1] or fraction - self._last[0] >= 0.05 or fraction == 1:
                self.stream.write(f"[{100 * fraction:5.1f} %] {message}\n")
                self.stream.flush()
                self._last = (fraction, message)
            return
        if not self.enabled:
            return
        filled = int(round(self.width * fraction))
        self.stream.write(f"\r[{'#' * filled}{'.' * (self.width - filled)}] {100 * fraction:5.1f} % {message[:50]:<50}")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\r" + " " * (self.width + 60) + "\r")
            self.stream.flush()


def _bar(args) -> _ProgressBar:
    return _ProgressBar(mode=getattr(args, "progress", "auto"))


def _cmd_bifurcation(args) -> int:
    from .analyses.diagrams.bifurcation import BifurcationOptions, bifurcation

    ntst = _limit("bifurcation", "ntst", args.ntst)
    ds_max = check_number("ds_max", args.ds_max, 1e-3, 10.0)
    options = BifurcationOptions(ntst=ntst, ds=min(BifurcationOptions.ds, ds_max), ds_max=ds_max,
                                 exact_nes=args.exact_nes, seeds=not args.no_seeds)
    bar = _bar(args)
    try:
        result = bifurcation(args.config, args.Fz, v_range=(args.v_min, args.v_max), params=_params(args),
                             options=options, progress=bar)
    finally:
        bar.close()
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
    _emit(result.to_dict(), args.json, "\n".join(lines))
    return 0


def _cmd_hopf_curves(args) -> int:
    from .analyses.diagrams.hopf_curves import hopf_curves

    bar = _bar(args)
    try:
        result = hopf_curves(args.config, params=_params(args), v_range=(args.v_min, args.v_max),
                             fz_range=(args.fz_min, args.fz_max), progress=bar)
    finally:
        bar.close()
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
    _emit(result.to_dict(), args.json, "\n".join(lines))
    return 0


def _cmd_curves(args) -> int:
    from .analyses.diagrams.cycle_curves import KEY_OF_KIND, KINDS, cycle_curves

    kinds = tuple(k.strip().upper() for k in str(args.kinds).split(",") if k.strip())
    for k in kinds:
        if k not in KINDS:
            raise InvalidParameterError("kinds", args.kinds, "comma-separated kinds among lpc, ns, pd",
                                        f"names an unknown kind ({k.lower()})")
    loads = tuple(_float_list("at_fz", args.at_fz)) if args.at_fz else ()
    bar = _bar(args)
    try:
        result = cycle_curves(args.config, params=_params(args), v_range=(args.v_min, args.v_max),
                              fz_range=(args.fz_min, args.fz_max), kinds=kinds, loads=loads, progress=bar)
    finally:
        bar.close()
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
    _emit(data, args.json, "\n".join(lines))
    return 0


def _float_list(name: str, text: str) -> list[float]:
    items = [t.strip() for t in str(text).split(",") if t.strip()]
    try:
        return [float(t) for t in items]
    except ValueError:
        raise InvalidParameterError(name, text, "comma-separated numbers, e.g. 0.0005,0.001,0.005") from None


def _cmd_map(args) -> int:
    from .analyses.maps.design_metrics import metrics
    from .analyses.maps.stability_map import SHIMMY_TYPES, stability_map

    resolution = _limit("map", "resolution", args.resolution)
    n_v = _limit("map", "n_v", args.n_v)
    bar = _bar(args)
    try:
        smap = stability_map(args.config, v_range=(args.v_min, args.v_max), fz_range=(args.fz_min, args.fz_max),
                             resolution=resolution, params=_params(args), n_v=n_v, progress=bar)
        figures = metrics(smap, Fz=_limit("map", "metrics_Fz", args.metrics_Fz))
    finally:
        bar.close()
    payload = smap.to_dict()
    payload["metrics"] = figures
    if args.csv:
        smap.write_csv(args.csv)
    counts = {t: sum(row.count(t) for row in smap.shading) for t in SHIMMY_TYPES}
    lines = [f"{smap.config.value}: {len(smap.Fz)} classified slices, {len(smap.shading_Fz)} x {len(smap.V)} grid, "
             f"V {smap.v_range[0]:g}.."
             f"{smap.v_range[1]:g} m/s, Fz {smap.fz_range[0]:g}..{smap.fz_range[1]:g} N "
             f"({smap.elapsed_s:.1f} s, {smap.executor})",
             "  grid points by type: " + ", ".join(f"{t} {n}" for t, n in counts.items())
             + f"; {len(smap.regions)} region polygons",
             f"  Hopf curves {len(smap.hopf.curves)}, GH points {len(smap.hopf.gh_points)}, "
             f"fold curves {len(smap.fold_curves)}, torus curves {len(smap.torus_curves)}"]
    if smap.min_shimmy:
        lines.append(f"  minimum shimmy load {smap.min_shimmy['Fz']:.6g} N at V = {smap.min_shimmy['V']:.5g} m/s "
                     f"({smap.min_shimmy['source']})")
    else:
        lines.append("  no shimmy anywhere in the map")
    lines.append(f"  pure-torsion area, Fz <= 250 kN: {figures['torsion_area']:.6g} (m/s) kN")
    lines += [f"  warning: {w}" for w in smap.warnings]
    _emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_classify(args) -> int:
    from .analyses.maps.stability_map import classify

    result = classify(args.config, args.V, args.Fz, params=_params(args), v_range=(args.v_min, args.v_max))
    lines = [f"{result['config']} at V = {result['V']:g} m/s, Fz = {result['Fz']:g} N: {result['shimmy_type']}"]
    for a in result["attractors"]:
        if a["kind"] == "equilibrium":
            lines.append("  stable: straight rolling x = 0")
        else:
            lines.append(f"  stable: {a['kind']} ({a['mode']}), max |psi| {a['max_psi']:.5g} rad, "
                         f"max |l_g delta| {a['max_lateral']:.5g} m")
    _emit(result, args.json, "\n".join(lines))
    return 0


def _cmd_metrics(args) -> int:
    from .analyses.maps.design_metrics import design_report

    resolution = _limit("map", "resolution", args.resolution)
    configs = [c.strip() for c in args.configs.split(",") if c.strip()]
    bar = _bar(args)
    try:
        report = design_report(configs, params=_params(args), Fz=float(check_number("Fz", args.Fz, *FZ_RANGE, "N")),
                               resolution=resolution, progress=bar)
    finally:
        bar.close()
    report.pop("maps")
    lines = [f"{'config':<8}{'min shimmy Fz (kN)':>20}{'change':>9}{'lateral min Fz (kN)':>21}{'change':>9}"
             f"{'torsion area':>14}{'change':>9}{'max psi (rad)':>15}{'change':>9}  shimmy V (m/s) at "
             f"{report['Fz'] / 1e3:g} kN"]
    for c, m in report["metrics"].items():
        d = m["against_original"]

        def rel(key):
            r = d[key]["relative"]
            return "" if r is None else f"{100 * r:+.1f}%"

        fz = "-" if m["min_shimmy_Fz"] is None else f"{m['min_shimmy_Fz'] / 1e3:.2f}"
        lat = "-" if m["lateral_min_Fz"] is None else f"{m['lateral_min_Fz'] / 1e3:.2f}"
        hull = m["at_Fz"]["shimmy_speed_range"]
        lines.append(f"{c:<8}{fz:>20}{rel('min_shimmy_Fz'):>9}{lat:>21}{rel('lateral_min_Fz'):>9}"
                     f"{m['torsion_area']:>14.1f}{rel('torsion_area'):>9}"
                     f"{m['at_Fz']['max_psi']:>15.5f}{rel('max_psi'):>9}  "
                     + ("none" if hull is None else f"{hull[0]:.1f}..{hull[1]:.1f}"))
    names = list(next(iter(report["metrics"].values()))["operating_points"])
    lines.append(f"\nshimmy type at the operating points{'':<2}" + "".join(f"{n:>10}" for n in names))
    for c, m in report["metrics"].items():
        lines.append(f"{c:<37}" + "".join(f"{m['operating_points'][n]:>10}" for n in names))
    _emit(report, args.json, "\n".join(lines))
    return 0


def _names(text: str | None) -> list[str] | None:
    return None if text is None else [n.strip() for n in str(text).split(",") if n.strip()]


def _cmd_sensitivity(args) -> int:
    from .analyses.decisions.sensitivity import sensitivity

    Fz = check_number("Fz", args.Fz, *FZ_RANGE, "N")
    result = sensitivity(args.config, Fz, params=_params(args), names=_names(args.params),
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
    _emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_optimise(args) -> int:
    from .analyses.decisions.optimise import FIGURES, optimise

    Fz = check_number("Fz", args.Fz, *FZ_RANGE, "N")
    bar = _bar(args)
    try:
        result = optimise(args.config, args.objective, parameters=_names(args.params), Fz=Fz,
                          constraints=args.constraint or [], params=_params(args), method=args.method,
                          starts=args.starts, local_runs=args.local_runs, seed=args.seed, progress=bar)
    finally:
        bar.close()
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
    _emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_robustness(args) -> int:
    from .analyses.decisions.robustness import robustness

    Fz = check_number("Fz", args.Fz, *FZ_RANGE, "N")
    bar = _bar(args)
    try:
        result = robustness(args.config, args.tolerance or [], samples=args.samples, Fz=Fz, params=_params(args),
                            seed=args.seed, progress=bar)
    finally:
        bar.close()
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
    _emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_study(args) -> int:
    from .analyses.decisions.studies import study, study_grid

    configs = [c.strip() for c in args.configs.split(",") if c.strip()]
    bar = _bar(args)
    try:
        if args.param2:
            values = (_float_list("values", args.values), _float_list("values2", args.values2 or ""))
            result = study_grid((args.param, args.param2), values, configs=configs, Fz=args.Fz, params=_params(args),
                                v_range=(args.v_min, args.v_max), progress=bar)
        else:
            result = study(args.param, _float_list("values", args.values), configs=configs, Fz=args.Fz,
                           params=_params(args), v_range=(args.v_min, args.v_max), progress=bar)
    finally:
        bar.close()
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
    _emit(result.to_dict(), args.json, "\n".join(lines))
    return 0


def _cmd_calibrate(args) -> int:
    from .analyses.core.calibration import calibrate, format_report

    result = calibrate(_params(args))
    _emit(result.to_dict(), args.json, format_report(result))
    return 0


def _add_common(p: argparse.ArgumentParser, design: bool = True) -> None:
    p.add_argument("--json", action="store_true", help="write JSON to stdout")
    if design:
        p.add_argument("--set", action="append", metavar="NAME=VALUE",
                       help="override a parameter (repeatable); see 'params' for names and ranges")
        p.add_argument("--material", choices=sorted(MATERIALS), help="particle-damper material preset")


DESCRIPTION = """\
Nose-landing-gear shimmy and its suppression by a torsional nonlinear energy sink (NES) and a
particle damper (PD), in four configurations: original, nes, pd, nes_pd. Every command prints a
short table, or JSON with --json; bad input exits with status 2 and a message naming the field,
its value and what is allowed. Units are SI: V in m/s, Fz in N."""

EPILOG = """\
examples:
  python -m shimmy params
  python -m shimmy hopf --config nes --Fz 150000
  python -m shimmy simulate --config original --V 50 --Fz 850000 --t-end 60
  python -m shimmy map --config nes_pd --resolution 10 --json > map.json
  python -m shimmy study --param e_p --values 0.0005,0.001,0.005 --configs nes,nes_pd

'python -m shimmy COMMAND --help' describes a command and its options."""


def _limits(analysis: str, name: str) -> str:
    """" (LOW-HIGH UNIT)" of a field, for an option's help."""
    f = schemas.SCHEMAS[analysis].field(name)
    return f" ({f.low:g} to {f.high:g}{' ' + f.unit if f.unit else ''})"


class _Formatter(argparse.ArgumentDefaultsHelpFormatter):
    """Defaults shown where there is one (not "default: None" on a flag or an optional file)."""

    def _get_help_string(self, action):
        if action.default in (None, False) or action.default is argparse.SUPPRESS:
            return action.help
        return super()._get_help_string(action)


def _add_progress(p: argparse.ArgumentParser) -> None:
    p.add_argument("--progress", choices=("auto", "bar", "log", "none"), default="auto",
                   help="progress on stderr: a bar (bar), plain lines that work in scripts and notebooks (log), "
                        "nothing (none); auto draws the bar on a terminal and writes lines otherwise")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m shimmy", description=DESCRIPTION, epilog=EPILOG,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    configs = [c.value for c in Configuration]

    class sub:  # every command's --help opens with its description and shows the defaults
        @staticmethod
        def add_parser(name: str, help: str) -> argparse.ArgumentParser:
            p = commands.add_parser(name, help=help, description=help[0].upper() + help[1:] + ".",
                                    formatter_class=_Formatter)
            return p

    p = sub.add_parser("params", help="list every parameter with unit, default, range")
    _add_common(p, design=False)
    p.set_defaults(func=_cmd_params)

    p = sub.add_parser("hopf", help="Hopf points of straight rolling in V at one load")
    p.add_argument("--config", required=True, choices=configs, help="configuration")
    p.add_argument("--Fz", required=True, help="vertical load (N)")
    p.add_argument("--v-min", default=V_RANGE[0], help="lowest speed (m/s)")
    p.add_argument("--v-max", default=V_RANGE[1], help="highest speed (m/s)")
    _add_common(p)
    p.set_defaults(func=_cmd_hopf)

    def operating_point(p: argparse.ArgumentParser) -> None:
        p.add_argument("--config", required=True, choices=configs, help="configuration")
        p.add_argument("--V", required=True, help="forward speed (m/s)")
        p.add_argument("--Fz", required=True, help="vertical load (N)")
        _add_common(p)

    p = sub.add_parser("eigen", help="eigenvalues of straight rolling at one operating point")
    operating_point(p)
    p.set_defaults(func=_cmd_eigen)

    p = sub.add_parser("simulate", help="time history at one operating point")
    operating_point(p)
    p.add_argument("--t-end", default=60.0, help="simulated time (s)" + _limits("simulate", "t_end"))
    p.add_argument("--exact-nes", action="store_true", help="use the exact NES torque instead of the cubic")
    p.add_argument("--csv", metavar="FILE", help="write the time series to FILE")
    p.set_defaults(func=_cmd_simulate)

    p = sub.add_parser("ground-run", help="take-off, landing roll or taxi: V(t), Fz(t) from a profile")
    p.add_argument("--config", required=True, choices=[*configs, "all"], help="configuration, or all four compared")
    p.add_argument("--profile", required=True, metavar="takeoff|landing|taxi|FILE.csv",
                   help="a preset, or a CSV table of t (s), V (m/s), Fz (N) rows (optional header t,V,Fz)")
    p.add_argument("--profile-set", action="append", metavar="NAME=VALUE",
                   help="adjust a preset's setting (repeatable), e.g. V_rotate=75")
    p.add_argument("--psi-threshold", default=0.01, help="torsional amplitude counted as shimmy (rad)")
    p.add_argument("--lateral-threshold", default=0.001, help="lateral amplitude l_g delta counted as shimmy (m)")
    p.add_argument("--series-dt", default=0.01, help="sampling interval of the series in the JSON and CSV (s)")
    p.add_argument("--fold-torus", action="store_true",
                   help="also the crossings of the fold and torus curves of cycles (several seconds per configuration)")
    p.add_argument("--exact-nes", action="store_true", help="use the exact NES torque instead of the cubic")
    p.add_argument("--csv", metavar="FILE", help="write the series of one configuration to FILE")
    _add_common(p)
    p.set_defaults(func=_cmd_ground_run)

    p = sub.add_parser("bifurcation", help="bifurcation diagram in V: equilibrium and periodic branches")
    p.add_argument("--config", required=True, choices=configs, help="configuration")
    p.add_argument("--Fz", required=True, help="vertical load (N)")
    p.add_argument("--v-min", default=V_RANGE[0], help="lowest speed (m/s)")
    p.add_argument("--v-max", default=200.0, help="highest speed (m/s)")
    p.add_argument("--ntst", default=40, help="collocation mesh intervals" + _limits("bifurcation", "ntst"))
    p.add_argument("--ds-max", default=0.5, help="largest continuation step (scaled arclength)")
    p.add_argument("--no-seeds", action="store_true", help="do not look for branches by simulation")
    p.add_argument("--exact-nes", action="store_true", help="use the exact NES torque instead of the cubic")
    p.add_argument("--csv", metavar="FILE", help="write the branch points to FILE")
    _add_common(p)
    _add_progress(p)
    p.set_defaults(func=_cmd_bifurcation)

    p = sub.add_parser("hopf-curves", help="Hopf curves of straight rolling in (V, Fz) with GH points")
    p.add_argument("--config", required=True, choices=configs, help="configuration")
    p.add_argument("--v-min", default=V_RANGE[0], help="lowest speed (m/s)")
    p.add_argument("--v-max", default=V_RANGE[1], help="highest speed (m/s)")
    p.add_argument("--fz-min", default=FZ_RANGE[0], help="lowest load (N)")
    p.add_argument("--fz-max", default=FZ_RANGE[1], help="highest load (N)")
    _add_common(p)
    _add_progress(p)
    p.set_defaults(func=_cmd_hopf_curves)

    p = sub.add_parser("curves", help="fold, torus and period-doubling curves of cycles in (V, Fz)")
    p.add_argument("--config", required=True, choices=configs, help="configuration")
    p.add_argument("--kinds", default="lpc,ns,pd", help="comma-separated: lpc, ns, pd")
    p.add_argument("--v-min", default=1.0, help="lowest speed (m/s)")
    p.add_argument("--v-max", default=200.0, help="highest speed (m/s)")
    p.add_argument("--fz-min", default=FZ_RANGE[0], help="lowest load (N)")
    p.add_argument("--fz-max", default=FZ_RANGE[1], help="highest load (N)")
    p.add_argument("--at-fz", default="", help="loads (N, comma-separated) where each curve's crossings are located")
    _add_common(p)
    _add_progress(p)
    p.set_defaults(func=_cmd_curves)

    def plane(p: argparse.ArgumentParser) -> None:
        p.add_argument("--v-min", default=1.0, help="lowest speed (m/s)")
        p.add_argument("--v-max", default=200.0, help="highest speed (m/s)")
        p.add_argument("--fz-min", default=FZ_RANGE[0], help="lowest load (N)")
        p.add_argument("--fz-max", default=FZ_RANGE[1], help="highest load (N)")

    p = sub.add_parser("map", help="(V, Fz) stability map: Hopf, fold and torus curves, shimmy types")
    p.add_argument("--config", required=True, choices=configs, help="configuration")
    plane(p)
    p.add_argument("--resolution", default=DEFAULT_MAP_SLICES,
                   help="classified Fz slices, evenly spaced (one more is added through each region between the "
                        "curves that they miss)" + _limits("map", "resolution"))
    p.add_argument("--n-v", default=100, help="number of speeds per slice on the output grid" + _limits("map", "n_v"))
    p.add_argument("--metrics-Fz", default=150e3, help="load (N) of the speed-interval and amplitude metrics")
    p.add_argument("--csv", metavar="FILE", help="write the classified grid to FILE")
    _add_common(p)
    _add_progress(p)
    p.set_defaults(func=_cmd_map)

    p = sub.add_parser("classify", help="shimmy type and stable attractors at one operating point")
    operating_point(p)
    p.add_argument("--v-min", default=1.0, help="lowest speed of the diagram the answer is read from (m/s)")
    p.add_argument("--v-max", default=200.0, help="highest speed of that diagram (m/s)")
    p.set_defaults(func=_cmd_classify)

    p = sub.add_parser("metrics", help="design figures of merit of configurations against original")
    p.add_argument("--configs", default="original,nes,pd,nes_pd", help="comma-separated configurations")
    p.add_argument("--Fz", default=150e3, help="load (N) of the speed-interval and amplitude metrics")
    p.add_argument("--resolution", default=DEFAULT_MAP_SLICES,
                   help="classified Fz slices of each map" + _limits("map", "resolution"))
    _add_common(p)
    _add_progress(p)
    p.set_defaults(func=_cmd_metrics)

    p = sub.add_parser("sensitivity", help="derivatives of the Hopf speeds, the minimum shimmy load and the largest "
                                           "torsional amplitude with respect to every parameter")
    p.add_argument("--config", required=True, choices=configs, help="configuration")
    p.add_argument("--Fz", default=150e3, help="vertical load (N)")
    p.add_argument("--params", help="comma-separated parameter names (default: all)")
    p.add_argument("--no-amplitude", action="store_true",
                   help="skip the largest torsional amplitude (which needs one bifurcation diagram)")
    p.add_argument("--top", type=int, default=8, help="rows per quantity in the table")
    _add_common(p)
    p.set_defaults(func=_cmd_sensitivity)

    p = sub.add_parser("optimise", help="search device parameters for the best figure of merit under constraints")
    p.add_argument("--config", required=True, choices=configs, help="configuration")
    p.add_argument("--objective", default="min_shimmy_Fz", choices=("min_shimmy_Fz", "interval", "max_psi",
                                                                    "torsion_area"),
                   help="maximise min_shimmy_Fz; minimise the shimmy interval width or max_psi at --Fz, or the "
                        "pure-torsion area")
    p.add_argument("--Fz", default=150e3, help="load (N) of the figures at a load")
    p.add_argument("--params", help="comma-separated parameters to search in their ranges (default: the "
                                    "configuration's device parameters: r2,e_p,k_s,r3 with the NES, a_p,rho_p with "
                                    "the PD)")
    p.add_argument("--constraint", action="append", metavar="FIGURE[@Fz]<=VALUE",
                   help="constraint on a figure (repeatable), e.g. max_psi<=0.02 or min_shimmy_Fz>=80000")
    p.add_argument("--method", default="auto", choices=("auto", "gradient", "global"),
                   help="gradient: Sobol starts then SLSQP with analytic gradients; global: differential evolution")
    p.add_argument("--starts", default=8, type=int, help="start designs (gradient method)")
    p.add_argument("--local-runs", default=2, type=int, help="SLSQP runs from the best starts (gradient method)")
    p.add_argument("--seed", default=0, type=int, help="seed of the start designs")
    _add_common(p)
    _add_progress(p)
    p.set_defaults(func=_cmd_optimise)

    p = sub.add_parser("robustness", help="Hopf speeds, minimum shimmy load and shimmy at the operating points "
                                          "under parameter tolerances (quasi-Monte Carlo and linear propagation)")
    p.add_argument("--config", required=True, choices=configs, help="configuration")
    p.add_argument("--Fz", default=150e3, help="vertical load (N)")
    p.add_argument("--tolerance", action="append", metavar="NAME=REL[:normal|uniform]",
                   help="relative tolerance of a parameter (repeatable): standard deviation (normal, the default) "
                        "or half-width (uniform), e.g. k_lam=0.05")
    p.add_argument("--samples", default=128, type=int, help="quasi-Monte Carlo samples")
    p.add_argument("--seed", default=0, type=int, help="seed of the scrambled Sobol sequence")
    p.add_argument("--with-samples", action="store_true", help="include every sample's values in the JSON")
    _add_common(p)
    _add_progress(p)
    p.set_defaults(func=_cmd_robustness)

    p = sub.add_parser("study", help="parametric study: Hopf speeds and max amplitude against parameters")
    p.add_argument("--param", required=True, help="parameter name (see 'params')")
    p.add_argument("--values", required=True, help="comma-separated values")
    p.add_argument("--param2", help="second parameter for a two-parameter grid")
    p.add_argument("--values2", help="comma-separated values of the second parameter")
    p.add_argument("--configs", default="original,nes,pd,nes_pd", help="comma-separated configurations")
    p.add_argument("--Fz", default=150e3, help="vertical load (N)")
    p.add_argument("--v-min", default=1.0, help="lowest speed (m/s)")
    p.add_argument("--v-max", default=200.0, help="highest speed (m/s)")
    p.add_argument("--csv", action="store_true", help="write the table as CSV to stdout")
    _add_common(p)
    _add_progress(p)
    p.set_defaults(func=_cmd_study)

    p = sub.add_parser("devices", help="NES torque/stiffness and PD damping curves")
    p.add_argument("--v-max", default=2.0, help="largest PD tangential speed (m/s)" + _limits("devices", "v_max"))
    _add_common(p)
    p.set_defaults(func=_cmd_devices)

    p = sub.add_parser("calibrate", help="refit the unpublished constants and print residuals")
    _add_common(p)
    p.set_defaults(func=_cmd_calibrate)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (InvalidInputError, GeometryError) as exc:  # InvalidParameterError derives from the first
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except EXPECTED_ERRORS as exc:
        print(f"failed: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except BrokenPipeError:  # stdout closed early (| head): not an error of ours
        return 0
    except OSError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
