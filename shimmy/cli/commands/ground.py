"""``ground-run``: take-off, landing roll or taxi, from a preset or a CSV table of V(t), Fz(t)."""

from __future__ import annotations

from typing import Any

from ...errors import InvalidParameterError
from ...model.configurations import CONFIGURATION_NAMES
from ..answers import add_no_cache, answer, design, emit, numbers, request
from ..common import EXIT_FAILED, add_command, add_common, add_config, add_field, limit, parse_sets


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
    from ...analyses.ground.ground_profiles import PRESETS, preset, profile_from_table
    from ...analyses.ground.kicks import KICK_PRESETS

    settings = parse_sets(args.profile_set)
    if args.profile in PRESETS:
        return preset(args.profile, {k: v for k, v in settings.items()})
    if args.profile in KICK_PRESETS:
        return preset(KICK_PRESETS[args.profile]["preset"], {k: v for k, v in settings.items()})
    if settings:
        raise InvalidParameterError("--profile-set", args.profile_set,
                                    f"only with a preset ({', '.join([*PRESETS, *KICK_PRESETS])})",
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


def _kick(args) -> dict[str, Any]:
    """The kick's request fields from --kick, --kick-size, --kick-at-time, --kick-at-speed, each number checked as
    typed against its range (the size against that of the kick's kind)."""
    from ...analyses.ground.kicks import KINDS
    from ...model.parameters import check_number

    out: dict[str, Any] = {"kick": args.kick}
    for name in ("kick_size", "kick_at_time", "kick_at_speed"):
        value = getattr(args, name)
        if value is not None and name == "kick_size" and args.kick in KINDS:
            _, unit, largest, what = KINDS[args.kick]
            check_number(name, value, -largest, largest, f"{unit} (a kick in {args.kick}, the {what})")
        out[name] = None if value is None else limit("ground_run", name, value)
    return out


def _cmd_ground_run(args) -> int:
    from ...analyses.ground.ground_profiles import PRESETS
    from ...analyses.ground.kicks import KICK_PRESETS
    from ...analyses.ground.summaries import (comparison_dict, comparison_summary, ground_run_summary,
                                              write_ground_run_csv)

    profile = _profile(args)
    named = args.profile in PRESETS or args.profile in KICK_PRESETS
    body = {**numbers("ground_run", args, "psi_threshold", "lateral_threshold", "series_dt"),
            "fold_torus": args.fold_torus, "exact_nes": args.exact_nes, "params": design(args), **_kick(args),
            **({"preset": args.profile, "preset_options": profile.settings} if named
               else {"profile": profile.rows()})}
    configs = list(CONFIGURATION_NAMES) if args.config == "all" else [args.config]
    requests = [request("ground_run", {**body, "config": config}) for config in configs]  # all checked first
    runs = [answer(args, "ground_run", canonical) for canonical in requests]
    if len(runs) == 1:
        payload = runs[0].result
        if args.csv:
            write_ground_run_csv(payload, args.csv)
        text = ground_run_summary(payload)
    else:
        payload = comparison_dict(runs[0].result["profile"], {c: r.result for c, r in zip(configs, runs, strict=True)},
                                  sum(r.result["elapsed_s"] for r in runs))
        text = comparison_summary(payload)
    emit(payload, runs, args.json, text)
    return 0 if all(r.result["success"] for r in runs) else EXIT_FAILED


def add_parsers(commands) -> None:
    p = add_command(commands, "ground-run", "take-off, landing roll or taxi: V(t), Fz(t) from a profile",
                    _cmd_ground_run)
    add_config(p, extra=["all"], help="configuration, or all four compared")
    p.add_argument("--profile", required=True, metavar="takeoff|landing|taxi|runway_joint|touchdown_yaw|FILE.csv",
                   help="a preset, a scenario (runway_joint: the take-off with a yaw-rate kick of 1 rad/s at 60 m/s; "
                        "touchdown_yaw: the landing roll from a yaw of 0.05 rad at t = 0; the --kick options given "
                        "take the place of theirs), or a CSV table of t (s), V (m/s), Fz (N) rows (optional header "
                        "t,V,Fz)")
    p.add_argument("--profile-set", action="append", metavar="NAME=VALUE",
                   help="adjust a preset's setting (repeatable), e.g. V_rotate=75")
    add_field(p, "ground_run", "--kick", "a kick during the run: a jump of the yaw angle (psi) or the yaw rate (dpsi)")
    add_field(p, "ground_run", "--kick-size", "the kick's size: rad for psi (-0.5 to 0.5), rad/s for dpsi (-50 to 50)")
    add_field(p, "ground_run", "--kick-at-time", "when the kick comes (s, on the profile's clock, within the run)")
    add_field(p, "ground_run", "--kick-at-speed", "or at which speed (m/s): the first time the run reaches it")
    add_field(p, "ground_run", "--psi-threshold", "torsional amplitude counted as shimmy (rad)")
    add_field(p, "ground_run", "--lateral-threshold", "lateral amplitude l_g delta counted as shimmy (m)")
    add_field(p, "ground_run", "--series-dt", "sampling interval of the series in the JSON and CSV (s)")
    p.add_argument("--fold-torus", action="store_true",
                   help="also the crossings of the fold and torus curves of cycles (several seconds per configuration)")
    p.add_argument("--exact-nes", action="store_true", help="use the exact NES torque instead of the cubic")
    p.add_argument("--csv", metavar="FILE", help="write the series of one configuration to FILE")
    add_common(p)
    add_no_cache(p)
