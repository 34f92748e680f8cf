"""The short tables ``python -m shimmy`` prints for this family's results, rendered from their
``to_dict()``: a result read back from the shared cache reads exactly as one just computed.

Only definitions are imported here (no integrator, no solver), so that a cached answer is printed
without loading the numerics.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...model.units import kn, mm


def hopf_summary(result: dict[str, Any]) -> str:
    """The short table ``python -m shimmy hopf`` prints, from ``HopfResult.to_dict()``."""
    lines = [f"{result['config']} at Fz = {kn(result['Fz'])}, V in [{result['v_min']:g}, {result['v_max']:g}] m/s"]
    if not result["hopf_points"]:
        lines.append("  no Hopf point")
    for h in result["hopf_points"]:
        lines.append(f"  Hopf V = {h['V']:.6f} m/s  f = {h['frequency_hz']:.4f} Hz  {h['criticality']}"
                     f"  ({'loses' if h['destabilising'] else 'regains'} stability as V increases)")
    for iv in result["unstable_intervals"]:
        lines.append(f"  x = 0 unstable for V in [{iv[0]:.6g}, {iv[1]:.6g}] m/s")
    return "\n".join(lines)


def simulation_summary(result: dict[str, Any]) -> str:
    """The short table ``python -m shimmy simulate`` prints, from ``SimulationResult.to_dict()``."""
    amp = result["amplitude"]
    freq = "-" if result["frequency_hz"] is None else f"{result['frequency_hz']:.4f} Hz"
    return (f"{result['config']} at V = {result['V']:g} m/s, Fz = {kn(result['Fz'])}, "
            f"{result['options']['t_end']:g} s\n"
            f"  response        {result['response_type']}{'' if result['steady'] else ' (not yet steady)'}\n"
            f"  max |psi|       {amp['psi']:.6g} rad\n"
            f"  max |l_g delta| {mm(amp['lateral'])}\n"
            f"  frequency       {freq}\n"
            f"  {result['message']}"
            + "".join(f"\n  warning: {w}" for w in result.get("warnings", ())))


def devices_summary(devices: dict[str, Any]) -> str:
    """The lines ``python -m shimmy devices`` prints, from ``{"nes": NESCurve.to_dict(), "pd": [PDCurve.to_dict(),
    ...]}``: the NES's cubic coefficients and the cubic's error, then the PD's torsional
    damping of each design at six tangential speeds."""
    nes, pds = devices["nes"], devices["pd"]
    lines = [f"NES: k1 = {nes['k1']:.6g} N m/rad, k3 = {nes['k3']:.6g} N m/rad^3; cubic vs exact torque: "
             + ", ".join(f"{100 * e:.2f} % for |a| <= {a} rad" for a, e in nes["cubic_error_at"].items()),
             "PD torsional damping c_eq (N m s/rad) at tangential speed v (m/s):",
             "  " + f"{'v':>8}" + "".join(f"{c['material']:>12}" for c in pds)]
    for i in np.linspace(0, len(pds[0]["speed"]) - 1, 6).astype(int):
        lines.append("  " + f"{pds[0]['speed'][i]:>8.3g}"
                     + "".join(f"{c['torsional_damping'][i]:>12.5g}" for c in pds))
    return "\n".join(lines)
