"""The model's parts: ``devices`` (the NES and PD curves) and ``calibrate`` (the fitted constants)."""

from __future__ import annotations


from ..common import add_command, add_common, add_field, emit, limit, params


def _cmd_devices(args) -> int:
    from ...analyses.core.device_curves import nes_curve, pd_curves
    from ...analyses.core.summaries import devices_summary

    design = params(args)
    nes_c = nes_curve(params=design)
    pds = pd_curves(params=design, v_max=limit("devices", "v_max", args.v_max))
    payload = {"params": design.to_dict(), "nes": nes_c.to_dict(), "pd": [c.to_dict() for c in pds]}
    emit(payload, args.json, devices_summary(payload))
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

    p = add_command(commands, "calibrate", "refit the unpublished constants and print residuals", _cmd_calibrate)
    add_common(p)
