"""The model's parts: ``devices`` (the NES and PD curves) and ``calibrate`` (the fitted constants)."""

from __future__ import annotations

from ..answers import add_no_cache, answer, design, numbers, request
from ..answers import emit as emit_answer
from ..common import add_command, add_common, add_field, emit, params


def _cmd_devices(args) -> int:
    from ...analyses.core.summaries import devices_summary

    curves = answer(args, "devices", request("devices", {**numbers("devices", args, "v_max"), "params": design(args)}))
    payload = {k: curves.result[k] for k in ("params", "nes", "pd")}  # the cubic's error is in nes already
    emit_answer(payload, [curves], args.json, devices_summary(payload))
    return 0


def _cmd_calibrate(args) -> int:
    from ...analyses.core.calibration import calibrate

    result = calibrate(params(args))
    emit(result.to_dict(), args.json, result.summary_text())
    return 0


def add_parsers(commands) -> None:
    p = add_command(commands, "devices", "NES torque/stiffness and PD damping curves", _cmd_devices)
    add_field(p, "devices", "--v-max", "largest PD tangential speed (m/s)", limits=True)
    add_common(p)
    add_no_cache(p)

    p = add_command(commands, "calibrate", "refit the unpublished constants and print residuals", _cmd_calibrate)
    add_common(p)
