"""The model's parts: ``devices`` (the NES and PD curves) and ``calibrate`` (the fitted constants)."""

from __future__ import annotations

import numpy as np

from ..common import add_command, add_common, add_field, emit, limit, params


def _cmd_devices(args) -> int:
    from ...analyses.core.device_curves import nes_curve, pd_curves

    design = params(args)
    nes_c = nes_curve(params=design)
    pds = pd_curves(params=design, v_max=limit("devices", "v_max", args.v_max))
    payload = {"params": design.to_dict(), "nes": nes_c.to_dict(), "pd": [c.to_dict() for c in pds]}
    err = nes_c.cubic_error_at
    lines = [f"NES: k1 = {nes_c.k1:.6g} N m/rad, k3 = {nes_c.k3:.6g} N m/rad^3; cubic vs exact torque: "
             + ", ".join(f"{100 * e:.2f} % for |a| <= {a} rad" for a, e in err.items()),
             "PD torsional damping c_eq (N m s/rad) at tangential speed v (m/s):",
             "  " + f"{'v':>8}" + "".join(f"{c.material:>12}" for c in pds)]
    for i in np.linspace(0, pds[0].speed.size - 1, 6).astype(int):
        lines.append("  " + f"{pds[0].speed[i]:>8.3g}" + "".join(f"{c.torsional_damping[i]:>12.5g}" for c in pds))
    emit(payload, args.json, "\n".join(lines))
    return 0


def _cmd_calibrate(args) -> int:
    from ...analyses.core.calibration import calibrate, format_report

    result = calibrate(params(args))
    emit(result.to_dict(), args.json, format_report(result))
    return 0


def add_parsers(commands) -> None:
    p = add_command(commands, "devices", "NES torque/stiffness and PD damping curves", _cmd_devices)
    add_field(p, "devices", "--v-max", "largest PD tangential speed (m/s)", limits=True)
    add_common(p)

    p = add_command(commands, "calibrate", "refit the unpublished constants and print residuals", _cmd_calibrate)
    add_common(p)
