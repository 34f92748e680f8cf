"""Design figures of merit of a configuration, and their change against ``original``.

* ``min_shimmy_Fz`` (N): the lowest load at which any limit cycle is stable for some speed in
  the map's range: the lowest point of the Hopf curves (x = 0 loses stability), of the
  fold-of-cycles curves (subcritical regions reach below the Hopf curves), or of a slice
  classified other than Stable, whichever is lowest (:attr:`StabilityMap.min_shimmy`).
* ``lateral_min_Fz`` (N): the lowest load of the lateral Hopf curve (its critical eigenvector's
  elastic energy mostly in lateral bending), the located turning point: the lateral bending
  boundary, below which the lateral mode of straight rolling is stable at every speed;
* at a chosen load: the shimmy speed intervals (every maximal V interval of one type other than
  Stable, on the slice's fine grid of (v_max - v_min) / (10 (n_v - 1)) m/s), their hull, and the
  largest torsional amplitude of a stable limit cycle with its speed;
* ``torsion_area`` ((m/s) kN): the area of the pure-torsion (type Torsion) region in the
  low-load band Fz <= 250 kN, V 1-200 m/s: on each row of the map's shading (read off the
  continued curves, :mod:`shimmy.analyses.maps.map_shading`) the measure of V classified Torsion,
  exact for the read-off, integrated over Fz by the trapezoidal rule between the rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..diagrams.bifurcation import BifurcationOptions
from ...model.configurations import CONFIGURATION_NAMES, OPERATING_POINTS, Configuration
from ...model.parameters import DEFAULT_FZ, DEFAULT_MAP_SLICES, FZ_RANGE, Parameters
from ..core.executors import run_units
from ..core.response import ShimmyType
from .map_slices import BAND_FZ_MAX, BAND_V, classify, map_slice
from .stability_map import StabilityMap, stability_maps

BASELINE = "original"
_trapezoid = getattr(np, "trapezoid", None) or np.trapz  # numpy 2 renamed it


def torsion_area(smap: StabilityMap, fz_max: float = BAND_FZ_MAX) -> dict[str, Any]:
    """Area ((m/s) kN) of the Torsion region of a map below ``fz_max``, and its share of the band:
    the Torsion measure of each row of the shading read off the curves, trapezoidal in Fz."""
    Fz = np.asarray(smap.shading_Fz, float)
    length = np.array([row.get(ShimmyType.TORSION, 0.0) for row in smap.shading_lengths])
    top = min(fz_max, smap.fz_range[1])
    inside = Fz <= top
    f = Fz[inside]
    L = length[inside]
    if f.size and f[-1] < top and (~inside).any():  # close the band at fz_max by interpolation
        j = int(np.argmax(~inside))
        L = np.append(L, np.interp(top, Fz[j - 1:j + 1], length[j - 1:j + 1]))
        f = np.append(f, top)
    area = float(_trapezoid(L, f / 1e3)) if f.size > 1 else 0.0
    band = (smap.v_range[1] - smap.v_range[0]) * (top - smap.fz_range[0]) / 1e3
    return {"torsion_area": area, "torsion_area_fraction": area / band if band > 0 else None,
            "band": {"V": list(smap.v_range), "Fz": [smap.fz_range[0], top], "rows": int(f.size)}}


#: The grid of the speed metrics' slice (points over the speed range; the fine grid is ten times finer).
SPEED_N_V = 200


@dataclass(frozen=True, eq=False)
class SpeedMetricsUnit:
    """The slice the speed metrics at one load are read from: a unit of work, so that a map's service
    runner computes it beside the map's own units instead of after them."""

    config: Configuration
    Fz: float
    params: Parameters
    v_range: tuple[float, float] = BAND_V
    n_v: int = SPEED_N_V
    options: BifurcationOptions | None = None

    def run(self) -> dict[str, Any]:
        s = map_slice(self.config, self.Fz, v_range=(self.v_range[0], self.v_range[1]), n_v=self.n_v,
                      params=self.params, options=self.options)
        hull = None if not s.intervals else [s.intervals[0]["V_start"], s.intervals[-1]["V_end"]]
        return {"Fz": s.Fz, "shimmy_intervals": s.intervals, "shimmy_speed_range": hull,
                "hopf_points": [h["V"] for h in s.hopf_points], "max_psi": s.max_psi, "max_psi_V": s.max_psi_V,
                "grid_step": (self.v_range[1] - self.v_range[0]) / ((self.n_v - 1) * 10)}

    def describe(self) -> str:
        return f"speed metrics at Fz = {self.Fz / 1e3:.4g} kN"


def speed_metrics(config: Configuration | str, Fz: float, *, params: Parameters | None = None,
                  v_range: tuple[float, float] = BAND_V, n_v: int = SPEED_N_V,
                  options: BifurcationOptions | None = None) -> dict[str, Any]:
    """Shimmy speed intervals and the largest stable torsional amplitude at one load."""
    return SpeedMetricsUnit(Configuration.parse(config), Fz, params if params is not None else Parameters(),
                            v_range, n_v, options).run()


def metrics(smap: StabilityMap, *, Fz: float = DEFAULT_FZ, options: BifurcationOptions | None = None,
            at_fz: dict[str, Any] | None = None) -> dict[str, Any]:
    """All figures of merit of one configuration from its map (plus one slice at ``Fz``; ``at_fz``: that
    slice's figures, :class:`SpeedMetricsUnit` of the map's configuration, design and speed range, if
    computed already)."""
    lateral = smap.hopf.lateral_minimum
    out = {"config": smap.config.value, "min_shimmy_Fz": smap.min_shimmy_Fz, "min_shimmy": smap.min_shimmy,
           "lateral_min_Fz": None if lateral is None else lateral["Fz"], "lateral_min": lateral}
    out.update(torsion_area(smap))
    out["at_Fz"] = at_fz if at_fz is not None else speed_metrics(smap.config, Fz, params=smap.params,
                                                                 v_range=smap.v_range, options=options)
    return out


def _change(value, base):
    if value is None or base is None:
        return {"value": value, "original": base, "change": None, "relative": None}
    return {"value": value, "original": base, "change": value - base,
            "relative": (value - base) / base if base else None}


def against_baseline(m: dict[str, Any], base: dict[str, Any]) -> dict[str, Any]:
    """Each figure of merit with the baseline's value, the difference and the relative change."""
    at, at0 = m["at_Fz"], base["at_Fz"]
    hull, hull0 = at["shimmy_speed_range"] or [None, None], at0["shimmy_speed_range"] or [None, None]
    return {"min_shimmy_Fz": _change(m["min_shimmy_Fz"], base["min_shimmy_Fz"]),
            "lateral_min_Fz": _change(m["lateral_min_Fz"], base["lateral_min_Fz"]),
            "torsion_area": _change(m["torsion_area"], base["torsion_area"]),
            "max_psi": _change(at["max_psi"], at0["max_psi"]),
            "shimmy_onset_V": _change(hull[0], hull0[0]), "shimmy_end_V": _change(hull[1], hull0[1])}


def _operating_point_unit(task: tuple) -> dict[str, Any]:
    """Types at the operating points sharing one load (one diagram serves them all)."""
    config, Fz, names, params = task
    from ..diagrams.bifurcation import bifurcation

    result = bifurcation(config, Fz, v_range=(BAND_V[0], BAND_V[1]), params=params,
                         options=BifurcationOptions(mesh_check=False))
    return {name: classify(config, OPERATING_POINTS[name][0], Fz, params=params, v_range=BAND_V,
                           result=result) for name in names}


def operating_point_types(configs: Sequence[str], *, params: Parameters | None = None, executor=None,
                          progress: Callable[[float, str], None] | None = None) -> dict[str, dict[str, Any]]:
    """{config: {point: classify(...)}} at the nine operating points (docs/model.md)."""
    params = params if params is not None else Parameters()
    configs = [Configuration.parse(c).value for c in configs]
    by_load: dict[float, list[str]] = {}
    for name, (_, Fz) in OPERATING_POINTS.items():
        by_load.setdefault(Fz, []).append(name)
    tasks = [(c, Fz, names, params) for c in configs for Fz, names in by_load.items()]
    results = run_units(_operating_point_unit, tasks, executor, progress,
                        lambda t: f"{t[0]} at Fz = {t[1] / 1e3:g} kN")
    out: dict[str, dict[str, Any]] = {c: {} for c in configs}
    for task, answers in zip(tasks, results, strict=True):
        out[task[0]].update(answers)
    return {c: {name: out[c][name] for name in OPERATING_POINTS} for c in configs}


def design_report(configs: Sequence[str] = CONFIGURATION_NAMES, *, params: Parameters | None = None,
                  Fz: float = DEFAULT_FZ, resolution: int = DEFAULT_MAP_SLICES, executor=None,
                  progress: Callable[[float, str], None] | None = None) -> dict[str, Any]:
    """Maps and figures of merit of several configurations, each against ``original``."""
    configs = [Configuration.parse(c).value for c in configs]
    wanted = configs if BASELINE in configs else [BASELINE] + configs
    report = progress or (lambda fraction, message: None)
    results: dict[str, Any] = {}
    # all maps' units on the executor at once: no worker idles at the end of one map
    computed = stability_maps(wanted, v_range=BAND_V, fz_range=FZ_RANGE, resolution=resolution, params=params,
                              executor=executor, progress=lambda fraction, message: report(0.97 * fraction, message))
    maps: dict[str, StabilityMap] = dict(zip(wanted, computed, strict=True))
    for c in wanted:
        results[c] = metrics(maps[c], Fz=Fz)
    for c in configs:
        results[c]["against_original"] = against_baseline(results[c], results[BASELINE])
    points = operating_point_types(configs, params=params, executor=executor, progress=lambda fraction,
                                   message: report(0.99, f"operating points: {message}"))
    for c in configs:
        results[c]["operating_points"] = {name: a["shimmy_type"] for name, a in points[c].items()}
    return {"Fz": Fz, "resolution": resolution, "configs": configs, "metrics": {c: results[c] for c in configs},
            "maps": maps}


def design_report_summary(report: dict[str, Any]) -> str:
    """The tables ``python -m shimmy metrics`` prints for a :func:`design_report`: each configuration's
    figures of merit with their change against ``original``, then its shimmy type at the operating points."""
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
    return "\n".join(lines)
