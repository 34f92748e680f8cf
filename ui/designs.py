"""Design sessions without Dash: a design as a named thing that is saved in the browser, written to
and read from a JSON file, reopened by a link, and compared with others in tables of figures.

A design is a PD material preset and the parameter values that differ from it (the form of the
service's requests and of the URL, :mod:`ui.state`), a name and, where it matters, the
configuration it was saved for. Every value read back (a file, an entry of the browser's store,
which the client may have changed, or a design saved by an older shimmy whose ranges have
moved) is validated by the parameter definitions themselves (:meth:`Parameters.with_overrides`,
:class:`InvalidParameterError`); a refusal names the field, the value in its unit and what is
allowed, and nothing is dropped or clipped on the way.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence
from urllib.parse import parse_qs

from shimmy.continuation.kinds import CYCLE_BIFURCATIONS, PointKind
from shimmy.errors import InvalidParameterError
from shimmy.model.configurations import Configuration
from shimmy.model.parameters import MATERIALS, PARAMETER_SPECS, Parameters, check_number
from shimmy.version import __version__ as SHIMMY_VERSION

from . import merits, state
from .formats import significant, significant_or_whole, signed_or_whole, signed_percent

FORMAT = "shimmy design"
FORMAT_VERSION = 1
FILE_KEYS = ("format", "format_version", "name", "shimmy_version", "material", "config", "parameters", "units")
MAX_NAME = 80
MAX_SAVED = 30  # the browser's store travels with the panel's callbacks: a bound keeps them small
MAX_FILE_BYTES = 32 * 1024  # a design file is about 2 kB
COMPARE = (2, 4)  # designs in one comparison
CURRENT = "current"  # the compare selection's id of the design in the panel
CURRENT_NAME = "current design"
CONFIGS = tuple(c.value for c in Configuration)


class DesignError(ValueError):
    """A design (a file, a saved entry, a comparison) refused: ``problems`` says each thing wrong."""

    def __init__(self, what: str, problems: Sequence[str]):
        self.what, self.problems = what, list(problems)
        super().__init__(f"{what}: " + "; ".join(self.problems))


def _with_unit(name: str, value: Any) -> str:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return f"{name} = {significant(value, 6)} {PARAMETER_SPECS[name].unit}".rstrip()
    return f"{name} = {json.dumps(value)}"


def _refusal(name: str, value: Any, exc: InvalidParameterError) -> str:
    """'r2 = 0.5 m is out of range; allowed: a number in [0.07, 0.09] m' from the definitions' own error."""
    text = str(exc)
    head = f"{exc.field}={exc.value!r} "
    return f"{_with_unit(name, value)} {text[len(head):] if text.startswith(head) else text}"


def check_values(material: str, values: Mapping[str, Any]) -> tuple[dict[str, float], list[str]]:
    """(the values that differ from ``material``'s, problems): each value through the parameter
    definitions, then the whole set (rules across fields such as the NES roller's track)."""
    problems: list[str] = []
    if material not in MATERIALS:
        return {}, [f"material = {material!r} is not one of {', '.join(MATERIALS)}"]
    base = Parameters().with_material(material)
    good: dict[str, float] = {}
    for name, value in values.items():
        if name not in PARAMETER_SPECS:
            try:
                base.with_overrides({name: value})
            except InvalidParameterError as exc:  # with a close name, the list of all 38 is noise
                text = str(exc)
                problems.append(text.split("; allowed:")[0] if "(did you mean" in text else text)
            continue
        if isinstance(value, (str, bool)) or value is None:  # JSON: numbers are numbers
            problems.append(f"{_with_unit(name, value)} is not a number; allowed: {PARAMETER_SPECS[name].allowed}")
            continue
        spec = PARAMETER_SPECS[name]
        try:  # the field's own range here; the rules across fields on the whole set below
            good[name] = check_number(name, value, spec.low, spec.high, spec.unit, spec.integer)
        except InvalidParameterError as exc:
            problems.append(_refusal(name, value, exc))
    if not problems:
        try:
            base.with_overrides(good)
        except InvalidParameterError as exc:
            name = exc.field if exc.field in PARAMETER_SPECS else ""
            text = _refusal(name, exc.value, exc) if name else str(exc)
            preset = base.to_dict()
            group = PARAMETER_SPECS[name].group if name else None
            moved = [_with_unit(n, v) for n, v in good.items() if v != preset[n] and PARAMETER_SPECS[n].group == group]
            problems.append(text + (f" (this design sets {', '.join(moved)})" if moved else ""))
    if problems:
        return {}, problems
    return state.design_request(material, {**state.material_params(material), **good})["params"], []


def _name_problem(name: Any) -> str | None:
    if not isinstance(name, str) or not name.strip():
        return f"name = {name!r} is not a name; give some text (at most {MAX_NAME} characters)"
    if len(name.strip()) > MAX_NAME:
        return f"name is {len(name.strip())} characters long; at most {MAX_NAME}"
    return None


@dataclass(frozen=True)
class Design:
    """A named design: material, the values that differ from it, and perhaps its configuration."""

    name: str
    material: str = state.DEFAULT_MATERIAL
    params: dict[str, float] = field(default_factory=dict)
    config: str | None = None

    @classmethod
    def make(cls, name: Any, material: Any, values: Mapping[str, Any], config: Any = None,
             what: str = "the design") -> "Design":
        """A design from untrusted parts, every one checked; DesignError lists all that is wrong."""
        problems = [p for p in (_name_problem(name),) if p]
        if not isinstance(material, str) or material not in MATERIALS:
            problems.append(f"material = {material!r} is not one of {', '.join(MATERIALS)}")
        elif not isinstance(values, Mapping):
            problems.append(f"parameters are a {type(values).__name__}, not an object {{name: value}}")
        else:
            overrides, bad = check_values(material, values)
            problems += bad
        if config is not None and config not in CONFIGS:
            problems.append(f"config = {config!r} is not one of {', '.join(CONFIGS)}")
        if problems:
            raise DesignError(what, problems)
        return cls(name.strip(), material, overrides, config)

    @property
    def values(self) -> dict[str, float]:
        """Every parameter value (SI units, as the model takes them)."""
        return {**state.material_params(self.material), **self.params}

    def request(self) -> dict[str, Any]:
        """The {"material", "params"} part of a service request."""
        return {"material": self.material, "params": dict(self.params)}

    def same(self, other: "Design") -> bool:
        """The same parameter values (whatever the names, the material presets or the configuration)."""
        return self.values == other.values

    def query(self) -> dict[str, str | None]:
        """The URL's design keys for this design, exact (repr): every parameter key, None where the
        material's value holds (so an old value in the address is removed), and the configuration."""
        out: dict[str, str | None] = {name: None for name in PARAMETER_SPECS}
        out.update({name: repr(float(v)) for name, v in self.params.items()})
        out["material"] = None if self.material == state.DEFAULT_MATERIAL else self.material
        if self.config is not None:
            out["config"] = self.config
        return out

    def changes(self) -> list[str]:
        """The values that differ from the material preset, in their units: 'r2 = 0.085 m'."""
        return [_with_unit(name, self.params[name]) for name in PARAMETER_SPECS if name in self.params]

    def summary(self) -> str:
        head = self.material + (f", {self.config}" if self.config else "")
        return head + (": " + ", ".join(self.changes()) if self.params else ": preset values")

    # -- the JSON file -------------------------------------------------------------------------

    def file(self) -> dict[str, Any]:
        """The JSON object of a design file: every parameter value, with its unit."""
        out: dict[str, Any] = {"format": FORMAT, "format_version": FORMAT_VERSION, "name": self.name,
                               "shimmy_version": SHIMMY_VERSION, "material": self.material}
        if self.config is not None:
            out["config"] = self.config
        out["parameters"] = self.values
        out["units"] = {name: spec.unit for name, spec in PARAMETER_SPECS.items()}
        return out

    def text(self) -> str:
        return json.dumps(self.file(), indent=1, allow_nan=False) + "\n"

    def filename(self) -> str:
        stem = re.sub(r"[^A-Za-z0-9._-]+", "_", self.name).strip("._") or "design"
        return f"{stem[:60]}.json"

    # -- the browser's store -------------------------------------------------------------------

    def entry(self, design_id: str) -> dict[str, Any]:
        return {"id": design_id, "name": self.name, "material": self.material, "params": dict(self.params),
                "config": self.config}


def from_file(content: str | bytes, filename: str = "the file") -> tuple[Design, list[str]]:
    """(the design, notes) of a design file; DesignError naming every problem otherwise.

    Notes say what was assumed (a material or a name not given, the parameters not given kept at
    the material's values, another shimmy version): nothing is assumed silently."""
    what = filename or "the file"
    if len(content) > MAX_FILE_BYTES:
        raise DesignError(what, [f"is {len(content) / 1024:.0f} kB; a design file is a few kB "
                                 f"(at most {MAX_FILE_BYTES // 1024} kB)"])
    if isinstance(content, bytes):
        try:
            content = content.decode("utf-8-sig")
        except UnicodeDecodeError:
            raise DesignError(what, ["is not UTF-8 text: is it a design file (.json)?"]) from None

    def no_constant(name):
        raise ValueError(f"{name} is not a number")

    try:
        data = json.loads(content, parse_constant=no_constant)
    except json.JSONDecodeError as exc:
        raise DesignError(what, [f"is not JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})"]) from None
    except ValueError as exc:
        raise DesignError(what, [f"is not valid JSON: {exc}"]) from None
    if not isinstance(data, dict):
        raise DesignError(what, [f"holds a JSON {type(data).__name__}, not a design (an object with format, "
                                 "name, material and parameters)"])
    problems, notes = [], []
    if data.get("format") != FORMAT:
        problems.append(f"format = {data.get('format')!r}, not {FORMAT!r}: is it a shimmy design file?"
                        if "format" in data else f"has no \"format\": {FORMAT!r}: is it a shimmy design file?")
    version = data.get("format_version", FORMAT_VERSION)
    if isinstance(version, bool) or not isinstance(version, int) or not 1 <= version <= FORMAT_VERSION:
        problems.append(f"format_version = {version!r}: this shimmy reads design files of version "
                        f"{FORMAT_VERSION}")
    unknown = [k for k in data if k not in FILE_KEYS]
    if unknown:
        problems.append(f"unknown key{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))}; "
                        f"allowed: {', '.join(FILE_KEYS)}")
    parameters = data.get("parameters", {})
    if not isinstance(parameters, dict):
        problems.append(f"parameters is a JSON {type(parameters).__name__}, not an object {{name: value}}")
        parameters = {}
    units = data.get("units", {})
    if not isinstance(units, dict):
        problems.append(f"units is a JSON {type(units).__name__}, not an object {{name: unit}}")
        units = {}
    for name, unit in units.items():
        spec = PARAMETER_SPECS.get(name)
        if spec is not None and unit != spec.unit:  # a value written in another unit would be misread
            problems.append(f"units: {name} is given in {unit!r}, but shimmy takes it in {spec.unit!r}; "
                            f"write its value in {spec.unit or 'no unit'}")
        elif spec is None and name not in parameters:
            problems.append(f"units: unknown parameter {name!r}")
    material = data.get("material")
    if material is None:
        material = state.DEFAULT_MATERIAL
        notes.append(f"no material given: {material}")
    name = data.get("name")
    if name is None:
        name = re.sub(r"\.json$", "", filename or "", flags=re.I) or "design"
        notes.append(f"no name given: named {name!r}")
    config = data.get("config")
    try:
        design = Design.make(name, material, parameters, config, what)
    except DesignError as exc:
        problems += exc.problems
    if problems:
        raise DesignError(what, problems)
    missing = [n for n in PARAMETER_SPECS if n not in parameters]
    if missing:
        notes.append(f"{len(missing)} parameter{'s' if len(missing) > 1 else ''} not given "
                     f"({', '.join(missing[:6])}{', ...' if len(missing) > 6 else ''}): "
                     f"the {design.material} values")
    written = data.get("shimmy_version")
    if written is not None and written != SHIMMY_VERSION:
        notes.append(f"written by shimmy {written}; this is shimmy {SHIMMY_VERSION}")
    return design, notes


# -- the designs saved in the browser ---------------------------------------------------------


def saved_list(data: Any) -> list[dict[str, Any]]:
    """The entries of the browser's store (a list of objects with an id; anything else is not ours)."""
    items = data.get("designs") if isinstance(data, dict) else None
    if not isinstance(items, list):
        return []
    return [e for e in items[:MAX_SAVED] if isinstance(e, dict) and isinstance(e.get("id"), str)]


def store(entries: list[dict[str, Any]]) -> dict[str, Any]:
    return {"designs": entries}


def from_entry(entry: Mapping[str, Any]) -> Design:
    """A saved entry as a design, checked again: the store is the client's, and the ranges may have
    changed since it was saved."""
    return Design.make(entry.get("name"), entry.get("material"), entry.get("params") or {}, entry.get("config"),
                       what=f"saved design {entry.get('name')!r}")


def usable(entry: Mapping[str, Any]) -> str | None:
    """Why a saved entry cannot be used (None if it can)."""
    try:
        from_entry(entry)
    except DesignError as exc:
        return "; ".join(exc.problems)
    return None


def _new_id(entries: list[dict[str, Any]]) -> str:
    taken = {e["id"] for e in entries}
    k = len(entries) + 1
    while f"d{k}" in taken:
        k += 1
    return f"d{k}"


def save(data: Any, design: Design) -> tuple[dict[str, Any], str, str]:
    """(the new store, the saved entry's id, what was done): a design of a name already saved
    replaces it (same id, so a comparison that holds it keeps it)."""
    entries = saved_list(data)
    for k, e in enumerate(entries):
        if e.get("name") == design.name:
            entries[k] = design.entry(e["id"])
            return store(entries), e["id"], f"Replaced the saved design {design.name!r}."
    if len(entries) >= MAX_SAVED:
        raise DesignError(f"saving {design.name!r}", [f"{MAX_SAVED} designs are saved in this browser, the most it "
                                                      "keeps; delete one first"])
    new = _new_id(entries)
    entries.append(design.entry(new))
    return store(entries), new, f"Saved {design.name!r} in this browser ({len(entries)} saved)."


def rename(data: Any, design_id: str, name: Any) -> tuple[dict[str, Any], str]:
    entries = saved_list(data)
    entry = next((e for e in entries if e["id"] == design_id), None)
    if entry is None:
        raise DesignError("rename", ["that design is no longer saved (deleted in another tab?)"])
    problem = _name_problem(name)
    if problem:
        raise DesignError(f"renaming {entry.get('name')!r}", [problem])
    name = name.strip()
    if any(e["name"] == name and e is not entry for e in entries):
        raise DesignError(f"renaming {entry.get('name')!r}", [f"{name!r} is the name of another saved design"])
    old, entry["name"] = entry.get("name"), name
    return store(entries), f"Renamed {old!r} to {name!r}."


def delete(data: Any, design_id: str) -> tuple[dict[str, Any], str]:
    entries = saved_list(data)
    gone = [e for e in entries if e["id"] == design_id]
    if not gone:
        return store(entries), "That design was already deleted."
    return store([e for e in entries if e["id"] != design_id]), f"Deleted {gone[0].get('name')!r}."


def find(data: Any, design_id: str) -> dict[str, Any] | None:
    return next((e for e in saved_list(data) if e["id"] == design_id), None)


def current_design(request: Any, name: str = CURRENT_NAME) -> Design:
    """The panel's design (its store: {"material", "params"}) as a design."""
    request = request if isinstance(request, dict) else {}
    return Design.make(name, request.get("material", state.DEFAULT_MATERIAL), request.get("params") or {},
                       what="the current design")


def matching(data: Any, current: Design) -> dict[str, Any] | None:
    """The saved entry with the current design's values, if any (the name box and the list say so)."""
    for entry in saved_list(data):
        try:
            if from_entry(entry).same(current):
                return entry
        except DesignError:
            continue
    return None


def config_from_search(search: Any) -> str | None:
    """The configuration a page's address names (?config=nes on the time history), if any."""
    if not isinstance(search, str) or len(search) > 8192:
        return None
    found = parse_qs(search.lstrip("?")).get("config", [None])[-1]
    return found if found in CONFIGS else None


# -- comparisons -------------------------------------------------------------------------------


def compared(selection: Any, data: Any, current_request: Any) -> list[Design]:
    """The designs ticked for a comparison, in the order of the list (the current design first):
    2 to 4 of them, each usable, no two the same. The first is the reference of the changes."""
    chosen = set(selection) if isinstance(selection, list) else set()
    designs: list[Design] = []
    if CURRENT in chosen:
        designs.append(current_design(current_request))
    problems = []
    for entry in saved_list(data):
        if entry["id"] in chosen:
            try:
                designs.append(from_entry(entry))
            except DesignError as exc:
                problems.append(str(exc))
    if problems:
        raise DesignError("comparison", problems)
    low, high = COMPARE
    if not low <= len(designs) <= high:
        raise DesignError("comparison", [f"{len(designs)} design{'' if len(designs) == 1 else 's'} ticked; tick "
                                         f"{low} to {high} under Compare in the design panel (saved designs, and "
                                         "the current one)"])
    for i, a in enumerate(designs):
        for b in designs[i + 1:]:
            if a.same(b):
                raise DesignError("comparison", [f"{a.name!r} and {b.name!r} are the same design (every parameter "
                                                 "equal): nothing to compare"])
    names = [d.name for d in designs]
    if CURRENT in chosen and names[0] in names[1:]:  # a saved design named like the current one
        designs[0] = Design("current design (unsaved)", designs[0].material, designs[0].params)
    return designs


@dataclass(frozen=True)
class Cell:
    """One design's value of one figure: its text, and its change against the first design."""

    text: str
    change: str | None = None  # None in the first design's column
    delta: Any = None  # the change as numbers (for a test, a CSV)


@dataclass(frozen=True)
class Figure:
    """A figure of merit: its label (with unit), how to read it from a result, how to show it."""

    label: str
    read: Callable[[dict[str, Any]], Any]
    kind: str = "number"  # number | list | range | ranges (a list of ranges) | text
    scale: float = 1.0  # shown = SI / scale
    unit: str = ""
    relative: bool = True  # also the change in per cent


def _zero(d: float, *values: float) -> bool:
    """A change that is rounding noise of the computation (1e-9 of the values), shown as "same"."""
    return abs(d) <= 1e-9 * max([1e-300, *(abs(v) for v in values)])


def _shown(f: Figure, value: Any) -> Any:
    if value is None:
        return None
    if f.kind == "list":
        return [v / f.scale for v in value]
    if f.kind == "range":
        return [value[0] / f.scale, value[1] / f.scale]
    if f.kind == "ranges":
        return [[a / f.scale, b / f.scale] for a, b in value]
    if f.kind == "number":
        return value / f.scale
    return value


def _text(f: Figure, v: Any) -> str:
    if f.kind == "number":
        return significant_or_whole(v)
    if f.kind == "list":
        return ", ".join(significant_or_whole(x) for x in v) if v else "none"
    if f.kind == "range":
        return "none" if v is None else f"{significant_or_whole(v[0])} – {significant_or_whole(v[1])}"
    if f.kind == "ranges":
        return "; ".join(f"{significant_or_whole(a)} – {significant_or_whole(b)}" for a, b in v) if v else "none"
    return "–" if v in (None, "") else str(v)


def _change(f: Figure, v: Any, b: Any) -> tuple[str, Any]:
    unit = f" {f.unit}" if f.unit else ""
    if f.kind == "text":
        return ("same" if v == b else "differs"), None
    if f.kind == "number":
        if v is None or b is None:
            return ("same" if v == b else f"{_text(f, b)} → {_text(f, v)}"), None
        d = v - b
        if _zero(d, v, b):
            return "same", 0.0
        text = f"{signed_or_whole(d)}{unit}"
        if f.relative and b != 0:
            text += f" ({signed_percent(100 * d / b)})"
        return text, d
    if f.kind == "range":
        if v is None or b is None:
            return ("same" if v == b else f"{_text(f, b)} → {_text(f, v)}"), None
        d = [v[0] - b[0], v[1] - b[1]]
        if all(_zero(x, *v, *b) for x in d):
            return "same", d
        return f"onset {signed_or_whole(d[0])}, end {signed_or_whole(d[1])}{unit}", d
    if f.kind == "ranges":
        v, b = v or [], b or []
        if len(v) != len(b):
            return f"{len(b)} → {len(v)} interval{'' if len(v) == 1 else 's'}", None
        d = [[x[0] - y[0], x[1] - y[1]] for x, y in zip(v, b, strict=True)]
        bounds = [x for pair in v + b for x in pair]
        if all(_zero(x, *bounds) for pair in d for x in pair):
            return "same", d
        return "; ".join(f"onset {signed_or_whole(x)}, end {signed_or_whole(y)}" for x, y in d) + unit, d
    # lists: element by element when they have as many entries
    v, b = v or [], b or []
    if len(v) != len(b):
        return f"{len(b)} → {len(v)} point{'' if len(v) == 1 else 's'}", None
    d = [x - y for x, y in zip(v, b, strict=True)]
    if all(_zero(x, p, q) for x, p, q in zip(d, v, b, strict=True)):
        return "same", d
    return ", ".join(signed_or_whole(x) for x in d) + unit, d


def comparison(names: Sequence[str], results: Sequence[dict[str, Any]], figures: Sequence[Figure]
               ) -> dict[str, Any]:
    """The figures of each design side by side: {"columns": ["figure", *names], "rows": [[label, Cell, ...]]};
    every design after the first with its change against the first."""
    rows = []
    for f in figures:
        values = []
        for r in results:
            try:
                values.append(_shown(f, f.read(r)))
            except (KeyError, TypeError, IndexError):
                values.append(None)
        cells = [Cell(_text(f, values[0]))]
        for v in values[1:]:
            text, delta = _change(f, v, values[0])
            cells.append(Cell(_text(f, v), text, delta))
        rows.append([f.label, *cells])
    return {"columns": ["figure", *names], "rows": rows}


def comparison_csv(table: dict[str, Any]) -> tuple[list[str], list[list[Any]]]:
    """The comparison as CSV rows: the value and the change of each design."""
    names = table["columns"][1:]
    columns = ["figure", *(c for k, n in enumerate(names) for c in ([n] if k == 0 else [n, f"{n}: change"]))]
    rows = [[row[0], *(x for k, cell in enumerate(row[1:]) for x in ([cell.text] if k == 0
                                                                       else [cell.text, cell.change]))]
            for row in table["rows"]]
    return columns, rows


def merit_figures(fz: float) -> list[Figure]:
    """The design figures of merit of a stability map (its ``metrics``), the speeds at load ``fz`` (N)."""
    at = f"at {fz / 1e3:g} kN"
    return [
        Figure("lowest shimmy load, min_shimmy_Fz (kN)", lambda m: m["min_shimmy_Fz"], scale=1e3, unit="kN"),
        Figure("lateral Hopf curve's lowest load, lateral_min_Fz (kN)", lambda m: m["lateral_min_Fz"], scale=1e3,
               unit="kN"),
        Figure(f"{merits.label('torsion_area')} ({merits.unit('torsion_area')})", lambda m: m["torsion_area"]),
        Figure(f"Hopf speeds {at} (m/s)", lambda m: m["at_Fz"]["hopf_points"], "list", unit="m/s"),
        Figure(f"shimmy speed range {at} (m/s)", lambda m: m["at_Fz"]["shimmy_speed_range"], "range", unit="m/s"),
        Figure(f"largest stable |psi| {at} (rad)", lambda m: m["at_Fz"]["max_psi"], unit="rad"),
        Figure(f"speed of that largest |psi| {at} (m/s)", lambda m: m["at_Fz"]["max_psi_V"], unit="m/s",
               relative=False),
    ]


def bifurcation_figures() -> list[Figure]:
    """What a bifurcation diagram says of a design: its Hopf points and its largest stable cycle."""
    def special(r, kinds=CYCLE_BIFURCATIONS):
        return sorted(sp["V"] for b in r["branches"] if b["kind"] == "periodic" for sp in b["special_points"]
                      if sp["kind"] in kinds)

    fold, torus, flip = PointKind.FOLD_OF_CYCLES, PointKind.TORUS, PointKind.PERIOD_DOUBLING
    return [
        Figure("Hopf points V (m/s)", lambda r: [h["V"] for h in r["hopf_points"]], "list", unit="m/s"),
        Figure("their criticality", lambda r: ", ".join(h["criticality"] for h in r["hopf_points"]) or "–", "text"),
        Figure("largest stable |psi| (rad)", lambda r: r["max_psi"], unit="rad"),
        Figure("speed of that largest |psi| (m/s)", lambda r: r["max_psi_V"], unit="m/s", relative=False),
        Figure(f"folds of cycles ({fold}) V (m/s)", lambda r: special(r, (fold,)), "list", unit="m/s"),
        Figure(f"torus ({torus}) and period-doubling ({flip}) V (m/s)", lambda r: special(r, (torus, flip)), "list",
               unit="m/s"),
        Figure("warnings", lambda r: "; ".join(r["warnings"]) or "–", "text"),
    ]


def hopf_figures(configs: Sequence[str], labels: Mapping[str, str]) -> list[Figure]:
    """Linear stability of straight rolling per configuration (the service's ``stability`` result):
    the speeds where it is unstable (between Hopf points), each bound's change."""
    return [Figure(f"{labels.get(c, c)}: x = 0 unstable for V in (m/s)",
                   lambda r, c=c: r["configs"][c]["unstable_intervals"], "ranges", unit="m/s") for c in configs]
