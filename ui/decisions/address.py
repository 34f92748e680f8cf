"""The Design decisions page's state in the address, in one place: the 13 keys it reads when the page
loads (each value refused by name if it cannot be used) and writes back as the controls change
(constraints and tolerances in the API's string form, SI units)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import dash
from dash import Input, Output

from shimmy.errors import InvalidParameterError
from shimmy.model.configurations import affects
from shimmy.model.parameters import DEFAULT_FZ
from shimmy.service import schemas
from ui import fields, ids
from ui.layout import DESIGN

from .common import CONFIGS, FIGURES, FZ, OPS
from .optimiser import OBJECTIVES, OPT_SEED, RUNS, STARTS, default_search
from .robustness import DEFAULT_TOLERANCES, ROB_SEED, SAMPLES, TOLERABLE
from .sensitivity import BARS, SHOWN

#: The page's keys (everything else in the address is the design's).
KEYS = ("config", "Fz", "bars", "show", "objective", "search", "cons", "starts", "runs", "opt_seed", "tols",
        "samples", "seed")


@dataclass(frozen=True)
class Address:
    """The controls' first values from the address and, for each, why the address's value was not used
    (``bad_*``, None if it was)."""

    config: str
    fz: float | None
    by: str
    shown: str
    goal: str
    chosen: list[str]
    constraint_rows: list[dict]
    n_starts: float | None
    n_runs: float | None
    o_seed: float | None
    tolerance_rows: list[dict]
    n_samples: float | None
    r_seed: float | None
    bad_config: str | None = None
    bad_fz: str | None = None
    bad_bars: str | None = None
    bad_show: str | None = None
    bad_objective: str | None = None
    bad_search: str | None = None
    bad_cons: str | None = None
    bad_starts: str | None = None
    bad_runs: str | None = None
    bad_oseed: str | None = None
    bad_tols: str | None = None
    bad_samples: str | None = None
    bad_rseed: str | None = None


def read(query: dict[str, Any]) -> tuple[Address, dict[str, Any]]:
    """(the page's state from its keys of the address, the address's other keys: the design's)."""
    config, Fz, bars, show, objective, search, cons, starts, runs, opt_seed, tols, samples, seed = (
        query.get(k) for k in KEYS)
    config, bad_config = fields.choice("config", config, list(CONFIGS), "nes", "a configuration")
    fz, bad_fz = FZ.from_url("Fz", Fz, 150)
    by, bad_bars = fields.choice("bars", bars, list(BARS), "per_half_range", "a bar scale")
    shown, bad_show = fields.choice("show", show, list(SHOWN), "device", "a parameter set")
    goal, bad_objective = fields.choice("objective", objective, list(OBJECTIVES), "min_shimmy_Fz", "an objective")
    chosen, bad_search = fields.choices_list("search", search, DESIGN, default_search(config), "a device parameter")
    chosen = [n for n in chosen if affects(n, config)]
    constraint_rows, bad_cons = _constraint_rows(cons)
    n_starts, bad_starts = STARTS.from_url("starts", starts, STARTS.spec.default)
    n_runs, bad_runs = RUNS.from_url("runs", runs, RUNS.spec.default)
    o_seed, bad_oseed = OPT_SEED.from_url("opt_seed", opt_seed, 0)
    tolerance_rows, bad_tols = _tolerance_rows(tols)
    n_samples, bad_samples = SAMPLES.from_url("samples", samples, 64)
    r_seed, bad_rseed = ROB_SEED.from_url("seed", seed, 0)
    state = Address(config, fz, by, shown, goal, chosen, constraint_rows, n_starts, n_runs, o_seed, tolerance_rows,
                    n_samples, r_seed, bad_config, bad_fz, bad_bars, bad_show, bad_objective, bad_search, bad_cons,
                    bad_starts, bad_runs, bad_oseed, bad_tols, bad_samples, bad_rseed)
    return state, {k: v for k, v in query.items() if k not in KEYS}


def _constraint_rows(raw: str | None) -> tuple[list[dict], str | None]:
    """Table rows from the address's cons=max_psi<=0.2,min_shimmy_Fz>=80000 (values in the API's SI units)."""
    rows, bad = [], []
    for k, text in enumerate(t for t in (raw or "").split(",") if t.strip()):
        try:
            c = schemas.constraint(f"cons[{k}]", text, DEFAULT_FZ)
        except InvalidParameterError as exc:
            bad.append(str(exc))
            continue
        rows.append({"figure": c["figure"], "op": c["op"], "value": c["value"] / FIGURES[c["figure"]][2]})
    return rows, (f"The address gives cons={raw}: {'; '.join(bad)}." if bad else None)


def _tolerance_rows(raw: str | None) -> tuple[list[dict], str | None]:
    rows, bad = [], []
    for k, text in enumerate(t for t in (raw if raw is not None else DEFAULT_TOLERANCES).split(",") if t.strip()):
        try:
            t = schemas.tolerance(f"tols[{k}]", text)
        except InvalidParameterError as exc:
            bad.append(str(exc))
            continue
        rows.append({"name": t["name"], "pct": round(100 * t["relative"], 10), "distribution": t["distribution"]})
    return rows, (f"The address gives tols={raw}: {'; '.join(bad)}." if bad else None)


@dash.callback(Output(ids.URL_UPDATE, "data", allow_duplicate=True),
               Input(ids.DES_CONFIG, "value"), Input(ids.DES_FZ, "value"), Input(ids.SENS_BY, "value"),
               Input(ids.SENS_SHOW, "value"), Input(ids.OPT_OBJECTIVE, "value"), Input(ids.OPT_SEARCH, "value"),
               Input(ids.OPT_CONSTRAINTS, "data"), Input(ids.OPT_STARTS, "value"), Input(ids.OPT_RUNS, "value"),
               Input(ids.OPT_SEED, "value"), Input(ids.ROB_TOLERANCES, "data"), Input(ids.ROB_SAMPLES, "value"),
               Input(ids.ROB_SEED, "value"), prevent_initial_call=True)
def remember(config, fz, by, shown, objective, search, constraints, starts, runs, opt_seed, tolerances, samples,
             seed):
    """The page's state in the address (constraints and tolerances in the API's string form, SI units)."""
    cons = []
    for row in constraints or []:
        if row.get("figure") in FIGURES and row.get("op") in OPS and isinstance(row.get("value"), (int, float)):
            cons.append(f"{row['figure']}{row['op']}{row['value'] * FIGURES[row['figure']][2]:g}")
    tols = []
    for row in tolerances or []:
        if row.get("name") in TOLERABLE and isinstance(row.get("pct"), (int, float)):
            dist = row.get("distribution") or "normal"
            tols.append(f"{row['name']}={row['pct'] / 100:g}" + ("" if dist == "normal" else f":{dist}"))
    return {"config": config, "Fz": fz, "bars": None if by == "per_half_range" else by,
            "show": None if shown == "device" else shown, "objective": objective, "search": ",".join(search or []),
            "cons": ",".join(cons), "starts": starts, "runs": runs, "opt_seed": opt_seed,
            "tols": ",".join(tols), "samples": samples, "seed": seed}
