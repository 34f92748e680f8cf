"""Maps: ``map`` (the (V, Fz) stability map), ``classify`` (one point of it), ``metrics`` (figures of
merit of configurations)."""

from __future__ import annotations

from ...model.configurations import CONFIGURATION_NAMES
from ...model.parameters import DEFAULT_FZ, DIAGRAM_V_RANGE, FZ_RANGE, check_number
from ..common import (add_command, add_common, add_config, add_field, add_operating_point, add_plane, add_progress,
                      emit, limit, params, progress)


def _cmd_map(args) -> int:
    from ...analyses.maps.design_metrics import metrics
    from ...analyses.maps.stability_map import SHIMMY_TYPES, stability_map

    resolution = limit("map", "resolution", args.resolution)
    n_v = limit("map", "n_v", args.n_v)
    with progress(args) as bar:
        smap = stability_map(args.config, v_range=(args.v_min, args.v_max), fz_range=(args.fz_min, args.fz_max),
                             resolution=resolution, params=params(args), n_v=n_v, progress=bar)
        figures = metrics(smap, Fz=limit("map", "metrics_Fz", args.metrics_Fz))
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
    emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_classify(args) -> int:
    from ...analyses.maps.stability_map import classify

    result = classify(args.config, args.V, args.Fz, params=params(args), v_range=(args.v_min, args.v_max))
    lines = [f"{result['config']} at V = {result['V']:g} m/s, Fz = {result['Fz']:g} N: {result['shimmy_type']}"]
    for a in result["attractors"]:
        if a["kind"] == "equilibrium":
            lines.append("  stable: straight rolling x = 0")
        else:
            lines.append(f"  stable: {a['kind']} ({a['mode']}), max |psi| {a['max_psi']:.5g} rad, "
                         f"max |l_g delta| {a['max_lateral']:.5g} m")
    emit(result, args.json, "\n".join(lines))
    return 0


def _cmd_metrics(args) -> int:
    from ...analyses.maps.design_metrics import design_report

    resolution = limit("map", "resolution", args.resolution)
    configs = [c.strip() for c in args.configs.split(",") if c.strip()]
    with progress(args) as bar:
        report = design_report(configs, params=params(args), Fz=float(check_number("Fz", args.Fz, *FZ_RANGE, "N")),
                               resolution=resolution, progress=bar)
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
    emit(report, args.json, "\n".join(lines))
    return 0


def add_parsers(commands) -> None:
    p = add_command(commands, "map", "(V, Fz) stability map: Hopf, fold and torus curves, shimmy types", _cmd_map)
    add_config(p)
    add_plane(p, "map")
    add_field(p, "map", "--resolution", "classified Fz slices, evenly spaced (one more is added through each region "
                                        "between the curves that they miss)", limits=True)
    add_field(p, "map", "--n-v", "number of speeds per slice on the output grid", limits=True)
    add_field(p, "map", "--metrics-Fz", "load (N) of the speed-interval and amplitude metrics")
    p.add_argument("--csv", metavar="FILE", help="write the classified grid to FILE")
    add_common(p)
    add_progress(p)

    p = add_command(commands, "classify", "shimmy type and stable attractors at one operating point", _cmd_classify)
    add_operating_point(p)
    p.add_argument("--v-min", default=DIAGRAM_V_RANGE[0],
                   help="lowest speed of the diagram the answer is read from (m/s)")
    p.add_argument("--v-max", default=DIAGRAM_V_RANGE[1], help="highest speed of that diagram (m/s)")

    p = add_command(commands, "metrics", "design figures of merit of configurations against original", _cmd_metrics)
    p.add_argument("--configs", default=",".join(CONFIGURATION_NAMES), help="comma-separated configurations")
    p.add_argument("--Fz", default=DEFAULT_FZ, help="load (N) of the speed-interval and amplitude metrics")
    add_field(p, "map", "--resolution", "classified Fz slices of each map", limits=True)
    add_common(p)
    add_progress(p)
