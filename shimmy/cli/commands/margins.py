"""Disturbances: at one operating point ``margins`` (how large a kick reaches each attractor) and ``basins`` (the
share of kicks up to a size that ends on each); over the plane ``margin-map`` (in each cell where torsional shimmy
coexists with another attractor, the smallest yaw kick that starts it)."""

from __future__ import annotations

from ...analyses.maps.margin_options import MIX_EXAMPLE
from ..answers import add_no_cache, answer, design, emit, numbers, request
from ..common import (add_command, add_common, add_config, add_field, add_operating_point, add_plane, add_progress,
                      progress)


def _ask(args, analysis: str, settings: tuple[str, ...], extra: dict | None = None):
    canonical = request(analysis, {"config": args.config, **numbers(analysis, args, "V", "Fz", *settings),
                                   **(extra or {}), "params": design(args)})
    with progress(args) as bar:
        return answer(args, analysis, canonical, bar)


def _cmd_margins(args) -> int:
    from ...analyses.maps.summaries import margins_summary

    result = _ask(args, "margins", ("max_size", "min_size", "scan_points", "rtol", "t_max", "phases"),
                  {"direction": args.direction, "mix": args.mix, "origin": args.origin})
    emit(result.result, [result], args.json, margins_summary(result.result))
    return 0


def _cmd_basins(args) -> int:
    from ...analyses.maps.summaries import basins_summary

    result = _ask(args, "basins", ("radius", "samples", "seed", "t_max"))
    emit(result.result, [result], args.json, basins_summary(result.result))
    return 0


def _cmd_margin_map(args) -> int:
    from ...analyses.maps.summaries import margin_map_summary

    canonical = request("margin_map", {"config": args.config, "params": design(args),
                                       **numbers("margin_map", args, "v_min", "v_max", "fz_min", "fz_max", "n_v",
                                                 "n_fz", "max_size")})
    with progress(args) as bar:
        result = answer(args, "margin_map", canonical, bar)
    emit(result.result, [result], args.json, margin_map_summary(result.result))
    return 0


def add_parsers(commands) -> None:
    p = add_command(commands, "margins", "disturbance margins at one operating point: its attractors and the "
                    "smallest kick (from straight rolling, or from the attractor the standard start reaches) that ends on each, "
                    "each checked by two runs", _cmd_margins)
    add_operating_point(p)
    add_field(p, "margins", "--direction", "the kicked component (the rest at rest), mix: the mix of --mix, or "
              "energy: all four, the smallest energy")
    add_field(p, "margins", "--mix", "with --direction mix: the components in their units, such as "
              f"'{MIX_EXAMPLE}' (only the direction counts)")
    add_field(p, "margins", "--origin", "kick straight rolling, or the attractor the standard start reaches (at "
              "--phases points of its orbit)")
    add_field(p, "margins", "--phases", "phases of the orbit kicked with --origin standard_attractor", limits=True)
    add_field(p, "margins", "--max-size", "largest kick scanned, as the yaw angle of the same energy",
              limits=True)
    add_field(p, "margins", "--min-size", "smallest kick scanned, as the yaw angle of the same energy",
              limits=True)
    add_field(p, "margins", "--scan-points", "sizes of the bracketing scan", limits=True)
    add_field(p, "margins", "--rtol", "relative tolerance of the bisection", limits=True)
    add_field(p, "margins", "--t-max", "longest run", limits=True)
    add_progress(p)
    add_no_cache(p)

    p = add_command(commands, "basins", "basin fractions at one operating point: the share of kicks up to a size "
                    "that ends on each attractor, with 95-percent intervals", _cmd_basins)
    add_operating_point(p)
    add_field(p, "basins", "--radius", "kicks uniform in the energy ball of this yaw angle", limits=True)
    add_field(p, "basins", "--samples", "kicks sampled", limits=True)
    add_field(p, "basins", "--seed", "seed of the samples", limits=True)
    add_field(p, "basins", "--t-max", "longest run", limits=True)
    add_progress(p)
    add_no_cache(p)

    p = add_command(commands, "margin-map", "disturbance margins on the map: in each cell of the plane where a "
                    "torsional cycle coexists with another attractor, the smallest yaw kick from straight rolling "
                    "that ends on it", _cmd_margin_map)
    add_config(p)
    add_plane(p, "margin_map")
    add_field(p, "margin_map", "--n-v", "cells in V, each asked at its centre", limits=True)
    add_field(p, "margin_map", "--n-fz", "cells in Fz, each asked at its centre", limits=True)
    add_field(p, "margin_map", "--max-size", "largest yaw kick scanned", limits=True)
    add_common(p)
    add_progress(p)
    add_no_cache(p)
