"""Maps: ``map`` (the (V, Fz) stability map), ``classify`` (one point of it), ``metrics`` (figures of
merit of configurations)."""

from __future__ import annotations

from ...model.configurations import CONFIGURATION_NAMES
from ...model.parameters import DEFAULT_FZ, DIAGRAM_V_RANGE, FZ_RANGE, check_number
from ..answers import add_no_cache, answer, design, numbers, request
from ..answers import emit as emit_answer
from ..common import (add_command, add_common, add_config, add_field, add_operating_point, add_plane, add_progress,
                      emit, limit, params, progress)


def _cmd_map(args) -> int:
    from ...analyses.maps.summaries import map_summary, write_map_csv

    canonical = request("map", {"config": args.config, "params": design(args),
                                **numbers("map", args, "v_min", "v_max", "fz_min", "fz_max", "resolution", "n_v",
                                          "metrics_Fz")})
    with progress(args) as bar:
        smap = answer(args, "map", canonical, bar)
    if args.csv:
        write_map_csv(smap.result, args.csv)
    emit_answer(smap.result, [smap], args.json, map_summary(smap.result))
    return 0


def _cmd_classify(args) -> int:
    from ...analyses.maps.map_slices import classification_summary, classify

    result = classify(args.config, args.V, args.Fz, params=params(args), v_range=(args.v_min, args.v_max))
    emit(result, args.json, classification_summary(result))
    return 0


def _cmd_metrics(args) -> int:
    from ...analyses.maps.design_metrics import design_report, design_report_summary

    resolution = limit("map", "resolution", args.resolution)
    configs = [c.strip() for c in args.configs.split(",") if c.strip()]
    with progress(args) as bar:
        report = design_report(configs, params=params(args), Fz=float(check_number("Fz", args.Fz, *FZ_RANGE, "N")),
                               resolution=resolution, progress=bar)
    report.pop("maps")
    emit(report, args.json, design_report_summary(report))
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
    add_no_cache(p)

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
