"""Response schemas: what each analysis answers, as JSON Schema (2020-12, the dialect of OpenAPI 3.1).

One declaration per analysis, used by the OpenAPI document (the 200 answer of ``POST /api/v1/NAME``
and the ``result`` of a done job) and checked against real answers by the service's tests
(tests/service/test_openapi_responses.py: every key of an answer is declared, every declared
required key is present, every value has its declared type). Units are SI as everywhere in the
JSON (N, m, m/s, rad, s); the workbench and the command line show loads in kN and l_g delta in mm.
"""

from __future__ import annotations

from typing import Any

Schema = dict[str, Any]

NUM: Schema = {"type": "number"}
INT: Schema = {"type": "integer"}
BOOL: Schema = {"type": "boolean"}
STR: Schema = {"type": "string"}


def num(description: str) -> Schema:
    return {"type": "number", "description": description}


def nullable(schema: Schema) -> Schema:
    """``schema`` or null (for a figure that may not exist, such as a minimum on a curve that has none)."""
    if isinstance(schema.get("type"), str):
        return {**schema, "type": [schema["type"], "null"]}
    return {"anyOf": [schema, {"type": "null"}]}


def arr(items: Schema, description: str | None = None, length: int | None = None) -> Schema:
    out: Schema = {"type": "array", "items": items}
    if length is not None:
        out["minItems"] = out["maxItems"] = length
    if description:
        out["description"] = description
    return out


def obj(required: dict[str, Schema], optional: dict[str, Schema] | None = None,
        description: str | None = None) -> Schema:
    """An object whose ``required`` keys are always there and whose ``optional`` ones may be."""
    out: Schema = {"type": "object", "required": list(required),
                   "properties": {**required, **(optional or {})}}
    if description:
        out["description"] = description
    return out


def mapping(values: Schema, description: str) -> Schema:
    """An object whose keys are names (parameters, configurations, operating points) and values ``values``."""
    return {"type": "object", "additionalProperties": values, "description": description}


def ref(name: str) -> Schema:
    return {"$ref": f"#/components/schemas/{name}"}


PAIR = arr(NUM, length=2)
NUMBERS = arr(NUM)
STRINGS = arr(STR)
VERSION = {"type": "string", "description": "the shimmy version that computed the result"}
ELAPSED = num("computing time (s)")
EXECUTOR = {"type": "string", "description": "where the units of work ran (local process pool, Dask cluster)"}
CONFIG = {"type": "string", "enum": ["original", "nes", "pd", "nes_pd"]}
METHODS = mapping(STR, "how each figure was computed, in words")
VP = obj({"V": num("speed (m/s)"), "Fz": num("vertical load (N)")})

#: Shared parts, each a component of the OpenAPI document.
COMPONENTS: dict[str, Schema] = {
    "Params": mapping(NUM, "the complete design: every parameter by name, in its unit (GET /api/v1/parameters)"),
    "Warnings": arr(STR, "what the computation noticed and the user should know (empty when nothing)"),
    "HopfPoint": obj({"V": num("speed (m/s)"), "frequency_hz": num("frequency of the crossing pair (Hz)"),
                      "criticality": {"type": "string", "enum": ["supercritical", "subcritical", "degenerate",
                                                                 "nonsmooth"]},
                      "lyapunov": nullable(num("first Lyapunov coefficient (null where the field is not smooth)")),
                      "destabilising": BOOL, "bracket": PAIR}),
    "Amplitudes": mapping(NUM, "amplitude of each state (psi, delta, lam, psis in rad; lateral = l_g delta in m)"),
    "Saddle": obj({"mode": STR, "amplitude": ref("Amplitudes"), "period": num("s"),
                   "branch": INT}, description="an unstable cycle between two attractors"),
    "Norm": obj({"energy": STR, "size": STR, "weights": mapping(NUM, "the energy's weights"),
                 "units": mapping(STR, "the weights' units")}),
    "Check": obj({"size": NUM, "unit": STR, "x0": NUMBERS, "ends_on": nullable(INT), "mode": STR,
                  "amplitude": mapping(nullable(NUM), "psi (rad) and lateral = l_g delta (m) where it ended"),
                  "t_s": num("s")}, description="a check run: its size, its whole start state x0 (a simulation's "
                                               "x0), where it ended"),
    "Attractor": obj({"kind": {"type": "string", "enum": ["equilibrium", "limit cycle", "quasi-periodic",
                                                          "unsettled", "simulation"]},
                      "mode": {"type": "string", "enum": ["torsional", "lateral", "both", "equilibrium"]},
                      "amplitude": ref("Amplitudes"), "period": nullable(num("s")), "source": STR,
                      "standard_start": BOOL},
                     {"min_disturbance": {"type": "object", "description": "the smallest disturbance found to end "
                                                                           "on this attractor", "properties": {
                         "value": nullable(NUM), "unit": STR, "direction": STR, "method": STR,
                         "tolerance": nullable(NUM), "rtol": NUM, "reached": BOOL, "lower": nullable(NUM),
                         "upper": nullable(NUM), "energy_J": nullable(NUM), "equivalent_psi": nullable(NUM),
                         "disturbance": nullable(mapping(NUM, "the disturbed state components")),
                         "mix": STR, "factor": NUM, "phase": NUM, "origin_state": NUMBERS,
                         "by_phase": arr(obj({"phase": NUM, "value": nullable(NUM)})),
                         "check": nullable(obj({"confirmed": BOOL},
                                               {"below": nullable(ref("Check")), "above": nullable(ref("Check"))})),
                         "note": STR},
                         "required": ["value", "unit", "direction", "method", "tolerance"]},
                      "basin": obj({"count": INT, "fraction": NUM, "ci95": PAIR})}),
}

_MARGIN_COMMON = {
    "config": CONFIG, "V": num("m/s"), "Fz": num("N"), "options": mapping({}, "the settings used"),
    "straight_rolling_stable": BOOL, "standard_start": INT, "saddles": arr(ref("Saddle")), "norm": ref("Norm"),
    "runs": INT, "elapsed_s": ELAPSED, "executor": EXECUTOR, "warnings": ref("Warnings"), "params": ref("Params"),
    "version": VERSION, "attractors": arr(ref("Attractor"))}

_CURVE_POINT = obj({"V": num("m/s"), "Fz": num("N")}, {"period": num("s"), "max_psi": num("rad"),
                                                      "max_lateral": num("m")})
_CODIM2 = obj({"V": num("m/s"), "Fz": num("N")}, {"kind": STR, "frequency_hz": NUM, "frequency2_hz": NUM,
                                                  "located": BOOL, "period": NUM, "max_psi": NUM,
                                                  "max_lateral": NUM, "turn": {"type": "string",
                                                                               "enum": ["min", "max"]}})
#: A special point of a one-parameter branch: its kind and speed, then its data, which depend on the kind
#: (H: frequency_hz, criticality, lyapunov; LPC, NS, PD: period, max_psi, max_lateral; NS: kappa).
_SPECIAL = {**obj({"kind": STR, "V": num("m/s")}, {
    "frequency_hz": NUM, "criticality": STR, "lyapunov": nullable(NUM), "period": NUM, "max_psi": NUM,
    "max_lateral": NUM, "located": BOOL, "kappa": NUM, "V_last_point": num("m/s: the branch point nearest it")}),
    "additionalProperties": {"description": "further data of the point's kind"}}
_SHIMMY_INTERVAL = obj({"type": STR, "V_start": num("m/s"), "V_end": num("m/s")})

#: The result of each analysis, by name.
RESULTS: dict[str, Schema] = {
    "simulate": obj({
        "config": CONFIG, "V": num("m/s"), "Fz": num("N"), "amplitude": ref("Amplitudes"),
        "frequency_hz": nullable(num("dominant frequency (Hz)")), "response_type": STR,
        "steady": BOOL, "success": BOOL, "message": STR,
        "counters": mapping(INT, "integrator counters"), "options": mapping({}, "the integrator's settings"),
        "params": ref("Params"), "version": VERSION,
        "start": obj({"psi0": num("rad"), "lateral0": num("m")}, {"x0": NUMBERS})},
        {"series": mapping(NUMBERS, "time series sampled every series_dt (t in s, angles in rad, lateral in m)"),
         "series_dt": num("s"),
         "spectrum": obj({"frequency_hz": NUMBERS, "psi": NUMBERS, "lateral": NUMBERS},
                         {"dominant_hz": nullable(NUM)}),
         "warnings": ref("Warnings")},
        "a time history from the start state (with include_series: its series and spectrum)"),
    "hopf": obj({
        "config": CONFIG, "Fz": num("N"), "v_min": num("m/s"), "v_max": num("m/s"), "params": ref("Params"),
        "hopf_points": arr(ref("HopfPoint")), "branch_points": arr({"type": "object"}),
        "unstable_intervals": arr(PAIR, "speed intervals (m/s) where straight rolling is unstable"),
        "success": BOOL, "message": STR, "warnings": ref("Warnings"), "n_grid": INT, "version": VERSION}),
    "stability": obj({
        "Fz": num("N"), "V": NUMBERS, "params": ref("Params"),
        "configs": mapping(obj({"max_real": arr(NUM, "largest real part of the eigenvalues (1/s) at each V"),
                                "frequency_hz": NUMBERS, "hopf_points": arr(ref("HopfPoint")),
                                "unstable_intervals": arr(PAIR)}), "per configuration")}),
    "devices": obj({
        "params": ref("Params"),
        "nes": obj({"angle": NUMBERS, "torque_exact": NUMBERS, "torque_cubic": NUMBERS, "stiffness_exact": NUMBERS,
                    "stiffness_cubic": NUMBERS, "k1": num("N m/rad"), "k3": num("N m/rad^3"),
                    "cubic_error_at": mapping(NUM, "relative error of the cubic at each angle (rad)")}),
        "nes_cubic_error": mapping(NUM, "relative error of the cubic fit at each angle (rad)"),
        "pd": arr(obj({"material": STR, "speed": NUMBERS, "rate": NUMBERS, "damping_per_speed": NUMBERS,
                       "torsional_damping": NUMBERS, "torque": NUMBERS}))}),
    "bifurcation": obj({
        "config": CONFIG, "Fz": num("N"), "v_min": num("m/s"), "v_max": num("m/s"), "params": ref("Params"),
        "hopf_points": arr(ref("HopfPoint")),
        "branches": arr(obj({"kind": STR, "origin": STR, "stop_reason": STR, "steps": INT,
                             "points": arr(obj({"V": num("m/s"), "period": nullable(num("s")),
                                                "max_psi": num("rad"), "max_lateral": num("m"), "stable": BOOL,
                                                "mode": nullable(STR)})),
                             "special_points": arr(_SPECIAL)})),
        "max_psi": nullable(num("largest stable |psi| (rad)")), "max_psi_V": nullable(num("m/s")),
        "max_psi_any": nullable(num("rad")), "mesh_check": nullable({"type": "object"}),
        "numerics": mapping({}, "ntst, ncol, steps, seeds, exact_nes"), "warnings": ref("Warnings"),
        "elapsed_s": ELAPSED, "version": VERSION}),
    "hopf_curves": obj({
        "config": CONFIG, "params": ref("Params"), "v_range": PAIR, "fz_range": PAIR,
        "curves": arr(obj({"points": arr(obj({"V": NUM, "Fz": NUM, "frequency_hz": NUM},
                                             {"lyapunov": nullable(NUM)})),
                           "gh_points": arr(_CODIM2), "fz_extrema": arr(VP), "double_hopf_points": arr(_CODIM2),
                           "zero_hopf_points": arr(_CODIM2), "closed": BOOL, "stop_reasons": STRINGS, "steps": INT})),
        "gh_points": arr(_CODIM2), "double_hopf_points": arr(_CODIM2),
        "lateral_minimum": nullable(_CODIM2), "fz_minimum": nullable(_CODIM2), "warnings": ref("Warnings"),
        "elapsed_s": ELAPSED, "version": VERSION}),
    "map": obj({
        "config": CONFIG, "params": ref("Params"), "v_range": PAIR, "fz_range": PAIR,
        "hopf_curves": arr(arr(VP)), "gh_points": arr(_CODIM2), "double_hopf_points": arr(_CODIM2),
        "fold_curves": arr(arr(_CURVE_POINT)), "torus_curves": arr(arr(_CURVE_POINT)),
        "cycle_curves": arr(obj({"kind": STR, "origin": STR, "points": INT, "closed": BOOL,
                                 "stop_reasons": STRINGS, "steps": INT},
                                {"fz_min": nullable(VP), "fz_max": nullable(VP), "turning_points": arr(_CODIM2),
                                 "crossings": arr(_CODIM2), "ends": arr(_CODIM2), "codim2_points": arr(_CODIM2)})),
        "codim2_points": arr(_CODIM2), "V": NUMBERS, "Fz": NUMBERS,
        "types": arr(STRINGS, "region type of each (Fz, V) grid cell: Stable, Torsion, Lateral, Bistable, Both, Latent"),
        "min_shimmy_Fz": nullable(num("lowest load with shimmy (N)")),
        "min_shimmy": nullable(obj({"Fz": NUM, "V": NUM, "source": STR})),
        "slices": arr({"type": "object"}, "the one-parameter diagram summary of each load"),
        "shading": obj({"V": NUMBERS, "Fz": NUMBERS, "types": arr(STRINGS)}, {"fallback_intervals": INT}),
        "regions": arr(obj({"type": STR, "V": NUMBERS, "Fz": NUMBERS})), "methods": METHODS,
        "executor": EXECUTOR, "warnings": ref("Warnings"), "elapsed_s": ELAPSED, "version": VERSION},
        {"metrics": {"type": "object", "description": "design figures of merit (minimum shimmy load, torsion "
                                                      "area, ...) at metrics_Fz"},
         "warmed_from": {"type": "object"}}),
    "study": obj({
        "parameters": STRINGS, "values": arr(NUMBERS), "configs": arr(CONFIG), "Fz": num("N"), "v_range": PAIR,
        "rows": arr({"type": "object", "description": "one design and configuration: the parameter values and "
                                                      "config, hopf_start, hopf_end (m/s), max_psi (rad), "
                                                      "max_psi_V (m/s), hopf_points, unstable_intervals, warnings",
                     "required": ["config"], "properties": {
                         "config": CONFIG, "hopf_start": nullable(NUM), "hopf_end": nullable(NUM),
                         "max_psi": nullable(NUM), "max_psi_V": nullable(NUM), "hopf_points": NUMBERS,
                         "unstable_intervals": arr(PAIR), "warnings": ref("Warnings")},
                     "additionalProperties": NUM}),
        "units": mapping(STR, "unit of each column"), "executor": EXECUTOR, "warnings": ref("Warnings"),
        "elapsed_s": ELAPSED, "version": VERSION,
        "curves": arr(obj({"config": CONFIG, "quantity": {"type": "string", "enum": [
            "hopf_V_start", "hopf_V_end", "min_shimmy_Fz", "max_psi", "gh_Fz", "gh_V", "double_hopf_Fz",
            "double_hopf_V"]}, "param": STR,
            "p": NUMBERS, "values": arr(nullable(NUM)),
            "special_points": arr(obj({"kind": STR, "p": NUM}, {"value": nullable(NUM), "V": {}, "Fz": NUM,
                                                               "located": BOOL, "bracket": PAIR, "why": STR})),
            "unit": STR}, {"point": {"type": "integer", "minimum": 1, "description": "which GH or double-Hopf "
                                     "point of the base design the curve follows (1, 2, ... by speed)"}}),
            "each figure continued in the parameter (one-parameter studies)")}),
    "ground_run": obj({
        "config": CONFIG, "time_in_shimmy_s": num("s"),
        "shimmy_intervals": arr(obj({"t_start": NUM, "t_end": NUM, "V_start": NUM, "V_end": NUM,
                                     "duration_s": NUM})),
        "speed_range": nullable(PAIR), "peak_psi": obj({"value": num("rad"), "t": NUM, "V": NUM, "Fz": NUM}),
        "peak_lateral": obj({"value": num("m"), "t": NUM, "V": NUM, "Fz": NUM}),
        "boundary_crossings": arr({"type": "object"}), "onsets": arr({"type": "object"}),
        "onset_delay_s": nullable(num("s")), "success": BOOL, "message": STR,
        "profile": obj({"name": nullable(STR), "rows": arr(arr(NUM, length=3)), "columns": STRINGS},
                       {"settings": nullable({"type": "object"}), "assumptions": nullable(STR)}),
        "options": mapping({}, "the run's settings"), "params": ref("Params"),
        "counters": mapping(INT, "integrator counters"), "elapsed_s": ELAPSED, "warnings": ref("Warnings"),
        "version": VERSION, "t": NUMBERS, "V": NUMBERS, "Fz": NUMBERS, "psi": NUMBERS, "lateral": NUMBERS,
        "envelope_psi": NUMBERS, "envelope_lateral": NUMBERS, "series_dt": num("s")},
        {"hopf_curves": arr(obj({"V": NUMBERS, "Fz": NUMBERS})), "cycle_curves": {"type": "object"},
         "psis": arr(NUM, "NES rotation (rad), with an NES"), "dpsis": arr(NUM, "its rate (rad/s)"),
         "nes_relative": arr(NUM, "NES relative rotation psi - psis (rad)"),
         "kick": nullable({"type": "object", "description": "the yaw kick of the run and what it started: kind, size, "
                                                           "unit, at_time or at_speed, t (s), applied, shimmy_started, "
                                                           "mode, without_kick, extra_time_in_shimmy_s, method; "
                                                           "null without a kick",
                           "required": ["kind", "size", "unit", "t", "applied", "shimmy_started", "mode"],
                           "properties": {
                               "kind": {"type": "string", "enum": ["psi", "dpsi"]}, "size": NUM, "unit": STR,
                               "at_time": nullable(num("s")), "at_speed": nullable(num("m/s")), "t": num("s"),
                               "V": nullable(num("m/s")), "Fz": nullable(num("N")),
                               "state_before": nullable(mapping(NUM, "the kicked components before the jump")),
                               "state_after": nullable(mapping(NUM, "the kicked components after the jump")),
                               "in_shimmy_before": nullable(BOOL), "applied": BOOL, "shimmy_started": nullable(BOOL),
                               "mode": nullable(STR), "t_judged": nullable(num("s")), "V_judged": nullable(num("m/s")),
                               "amplitude": nullable(mapping(NUM, "rad / m")), "peak": nullable({"type": "object"}),
                               "without_kick": nullable({"type": "object"}), "method": STR,
                               "extra_time_in_shimmy_s": nullable(num("s"))}})}),
    "sensitivity": obj({
        "config": CONFIG, "Fz": num("N"), "params": ref("Params"), "names": STRINGS,
        "hopf_points": arr({"type": "object"}), "min_shimmy_Fz": nullable({"type": "object"}),
        "max_psi": nullable({"type": "object"}), "no_effect": mapping(mapping(STR, ""), "why a parameter has "
                                                                                      "no effect"),
        "quantities": arr(obj({"key": STR, "label": STR, "unit": STR, "value": nullable(NUM),
                               "rows": arr({"type": "object"})})),
        "elapsed_s": mapping(NUM, "s per figure"), "methods": METHODS, "version": VERSION},
        {"warnings": ref("Warnings")}),
    "optimise": obj({
        "config": CONFIG, "objective": nullable(NUM), "objective_figure": {"type": "object"},
        "nominal_objective": nullable(NUM), "design": mapping(NUM, "the optimum's search parameters"),
        "parameters": STRINGS, "constraints": arr({"type": "object"}), "method": STR,
        "figures": mapping(mapping(nullable(NUM), ""), "figures of merit of the optimum, the nominal design and "
                                                      "original"),
        "evaluations": INT, "history": arr({"type": "object"}), "feasible": BOOL, "message": STR,
        "link_query": mapping(STR, "the workbench address of the optimum"), "params": ref("Params"),
        "elapsed_s": ELAPSED, "executor": EXECUTOR, "warnings": ref("Warnings"), "version": VERSION},
        {"at_bounds": arr(obj({"name": STR, "bound": {"type": "string", "enum": ["low", "high"]},
                                "limit": num("the bound, in the parameter's unit"), "value": NUM}),
                          "the searched parameters the optimum has on a bound of their range (within 0.1 % of it): "
                          "the range limits the optimum")}),
    "robustness": obj({
        "config": CONFIG, "Fz": num("N"), "params": ref("Params"),
        "tolerances": arr(obj({"name": STR, "relative": NUM, "distribution": STR}, {"relative_std": NUM})),
        "samples": INT, "seed": INT, "hopf_points": arr({"type": "object"}),
        "min_shimmy_Fz": nullable({"type": "object"}),
        "p_shimmy": mapping(nullable(NUM), "share of samples with unstable straight rolling, per operating point"),
        "p_shimmy_ci95": mapping(nullable(PAIR), "its 95 % Wilson interval, per operating point"),
        "disturbance": nullable({"type": "object", "description": "the stated disturbance (size, unit, direction); "
                                                                  "null without one"}),
        "p_shimmy_disturbed": nullable(mapping({"type": "object"}, "per operating point: P(shimmy | disturbance) "
                                                                   "with its interval and the share by mode")),
        "p_shimmy_linear": mapping(nullable(NUM), "the same from the linear propagation"),
        "operating_points": mapping(VP, "the operating points by name"), "refused_samples": INT,
        "elapsed_s": ELAPSED, "executor": EXECUTOR, "warnings": ref("Warnings"), "methods": METHODS,
        "version": VERSION}),
    "margins": obj({**_MARGIN_COMMON, "direction": STR, "unsettled_runs": INT,
                    "origin": obj({"kind": STR, "attractor": nullable(INT)},
                                  {"note": STR, "mode": STR, "period_s": num("s"), "phases": INT,
                                   "settled_at_s": num("s"), "warning": STR},
                                  "what the kicks were added to: straight rolling, or the attractor the standard "
                                  "start reaches (its period and the phases kicked)")}),
    "basins": obj({**_MARGIN_COMMON, "unsettled": INT, "failed": INT, "energy_J": num("J"), "method": STR}),
    "margin_map": obj({
        "config": CONFIG, "params": ref("Params"), "v_range": PAIR, "fz_range": PAIR,
        "grid": obj({"n_v": INT, "n_fz": INT}), "options": mapping({}, "the margin settings"), "direction": STR,
        "unit": STR, "worst": STR, "V": NUMBERS, "Fz": NUMBERS, "coexisting": arr(arr(INT)),
        "types": arr(STRINGS), "straight_rolling_stable": arr(arr(BOOL)),
        "points": arr(obj({"V": NUM, "Fz": NUM, "type": STR, "margin": nullable(num("rad")),
                           "attractors": arr({"type": "object"})},
                          {"straight_rolling_stable": BOOL, "worst": nullable(INT), "runs": INT,
                           "unsettled_runs": INT, "warnings": ref("Warnings"), "tolerance": nullable(NUM),
                           "lower": nullable(NUM), "upper": nullable(NUM), "reached": BOOL,
                           "confirmed": nullable(BOOL), "note": STR})),
        "smallest": nullable({"type": "object"}),
        "counts": {**mapping(INT, "cells of each kind (cells, multistable, bistable, computed, reached, zero, "
                                  "not_reached, unconfirmed)"),
                   "properties": {"by_type": mapping(INT, "computed cells by region type")}}, "method": mapping(STR, "how each part was found"),
        "diagrams_s": arr(NUM, "s per load's diagram")},
        {"elapsed_s": ELAPSED, "executor": EXECUTOR, "warnings": ref("Warnings"), "version": VERSION,
         "methods": METHODS}),
}

#: GET /api/v1/health (200 ok, 503 degraded with the cache's fault).
HEALTH = obj({"status": {"type": "string", "enum": ["ok", "degraded"]}, "version": VERSION,
              "time": num("server time (s since the epoch)")}, {"cache": STR})
#: GET /api/v1/parameters.
PARAMETERS = obj({"parameters": arr(obj({
    "name": STR, "group": STR, "unit": STR, "default": NUM, "low": NUM, "high": NUM, "description": STR,
    "provenance": STR, "integer": BOOL,
    "step": nullable(num("the engineering step of the workbench's slider and box (null: none set)"))}))})
