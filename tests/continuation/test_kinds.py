"""The kinds of special point are one enum, spelled only in ``shimmy/continuation/kinds.py``."""

import ast
import json
import pathlib

import pytest

from shimmy.continuation import PointKind

ROOT = pathlib.Path(__file__).resolve().parents[2]
VALUES = frozenset(k.value for k in PointKind)


@pytest.mark.parametrize("kind", list(PointKind))
def test_kind_round_trips_through_json(kind):
    text = json.dumps({"kind": kind})
    assert text == json.dumps({"kind": kind.value})
    back = json.loads(text)["kind"]
    assert PointKind(back) is kind
    assert f"{kind}" == str(kind) == kind.value


def _kind_name(name: str) -> bool:
    """A name that holds a kind or kinds: ``kind``, ``s.kind``, ``KINDS``, ``stop_at``."""
    return "kind" in name.lower() or name == "stop_at"


def _names_a_kind(node: ast.AST) -> bool:
    """``kind``, ``x.kind``, ``x["kind"]`` (and the plurals)."""
    if isinstance(node, ast.Name):
        return _kind_name(node.id)
    if isinstance(node, ast.Attribute):
        return _kind_name(node.attr)
    if isinstance(node, ast.Subscript):
        return isinstance(node.slice, ast.Constant) and node.slice.value in ("kind", "kinds")
    return False


def _kind_literals(node: ast.AST | None) -> list[ast.Constant]:
    """String constants equal to a kind's value: the node itself, or the items of a tuple, list or set."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in VALUES:
        return [node]
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return [c for e in node.elts for c in _kind_literals(e)]
    return []


def _spelled_kinds(tree: ast.AST) -> list[ast.Constant]:
    """Kinds written as strings where a kind is meant:

    * compared (``==``, ``!=``, ``in``) with a kind: ``s.kind == "LPC"``, ``kind in ("LPC", "NS")``,
      ``"LPC" in self.kinds``;
    * a kind table: a dict whose keys are all kinds' values (``{"H": "diamond", "LPC": ...}``), or
      the value of a ``"kind"`` key (``{"kind": "GH", "V": ...}``);
    * given or bound as a kind: the first argument of ``SpecialPoint``, a keyword, default or
      assignment whose name says kind (``kind="NS"``, ``KINDS = ("LPC", "NS")``, ``stop_at=("LPC",)``).

    Other strings equal to a value (an operating point "H" among "A".."G", a label "PD" of a
    configuration) are not kinds and are not flagged."""
    found: list[ast.Constant] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(_names_a_kind(s) for s in sides):
                found += [c for s in sides for c in _kind_literals(s)]
        elif isinstance(node, ast.Dict):
            keys = [k for k in node.keys if k is not None]
            if keys and all(_kind_literals(k) for k in keys):
                found += keys
            for k, v in zip(node.keys, node.values, strict=True):
                if isinstance(k, ast.Constant) and k.value in ("kind", "kinds"):
                    found += _kind_literals(v)
        elif isinstance(node, ast.Call):
            func = node.func
            callee = func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else ""
            if callee == "SpecialPoint" and node.args:
                found += _kind_literals(node.args[0])
            found += [c for kw in node.keywords if kw.arg and _kind_name(kw.arg) for c in _kind_literals(kw.value)]
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(_names_a_kind(t) for t in targets):
                found += _kind_literals(node.value)
        elif isinstance(node, ast.arguments):
            positional = node.posonlyargs + node.args
            pairs = list(zip(positional[len(positional) - len(node.defaults):], node.defaults, strict=True))
            pairs += [(a, d) for a, d in zip(node.kwonlyargs, node.kw_defaults, strict=True) if d is not None]
            found += [c for a, d in pairs if _kind_name(a.arg) for c in _kind_literals(d)]
    return found


def _offences(paths) -> list[str]:
    out = []
    for path in paths:
        if path.name == "kinds.py" and path.parent.name == "continuation":
            continue
        tree = ast.parse(path.read_text(), filename=str(path))
        out += [f"{path.relative_to(ROOT)}:{c.lineno}: {c.value!r}" for c in _spelled_kinds(tree)]
    return sorted(set(out))


def _python_files(*places: str) -> list[pathlib.Path]:
    files = []
    for place in places:
        path = ROOT / place
        files += [path] if path.is_file() else sorted(path.rglob("*.py"))
    return files


@pytest.mark.parametrize("source", [
    's.kind == "LPC"', 'kind in ("LPC", "NS")', 'x = {"H": "diamond", "LPC": "triangle"}',
    'SpecialPoint("EP", 1.0, 0)', 'y = {"kind": "GH", "V": 1.0}', 'sp["kind"] != "H"', 'KINDS = ("LPC", "NS")',
    'f(stop_at=("LPC",))', 'def f(r, kinds=("NS", "PD")): pass', '"LPC" in self.kinds'])
def test_the_scan_finds_spelled_kinds(source):
    assert _spelled_kinds(ast.parse(source))


@pytest.mark.parametrize("source", [
    'POINTS = {"A": (1.0, 2.0), "H": (110.0, 550e3)}', 'LABELS = {"nes": "NES", "pd": "PD"}',
    'b.kind == "periodic"', 'x = "NES + PD"', '"""H: a Hopf point."""', 'f("H")', 'kind == PointKind.HOPF'])
def test_the_scan_passes_other_strings(source):
    assert not _spelled_kinds(ast.parse(source))


def test_the_package_names_kinds_by_the_enum():
    assert _offences(_python_files("shimmy")) == []


def _ui_offences() -> list[str]:
    return _offences(_python_files("pages", "ui", "app.py"))


def test_the_ui_names_kinds_by_the_enum():
    assert _ui_offences() == []
