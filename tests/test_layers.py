"""The package's layers import only downward, and the numerics never import a UI."""

import ast
import pathlib

import shimmy

PACKAGE = pathlib.Path(shimmy.__file__).parent
MODEL = {"errors", "parameters", "configurations", "nes", "particle_damper", "equations", "integrator",
         "reference_model", "lyapunov", "response"}
ANALYSES = {"simulation", "stability", "calibration", "device_curves", "continuation", "collocation",
            "periodic_orbits", "bifurcation", "hopf_continuation", "hopf_curves", "executors", "stability_map",
            "studies", "design_metrics"}
FORBIDDEN = {"dash", "plotly", "flask", "gunicorn", "diskcache"}


def imports(path):
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: from .x import y / from . import x
                if node.module:
                    found.add("shimmy." + node.module.split(".")[0])
                else:
                    found |= {"shimmy." + a.name for a in node.names}
            else:
                found.add(node.module.split(".")[0])
    return found


def test_model_modules_do_not_import_analyses_or_ui():
    for name in MODEL:
        deps = imports(PACKAGE / f"{name}.py")
        assert not deps & FORBIDDEN, name
        assert not {d for d in deps if d.startswith("shimmy.")} & {f"shimmy.{a}" for a in ANALYSES | {"cli"}}, name


def test_analyses_do_not_import_the_ui_or_the_cli():
    for name in ANALYSES:
        deps = imports(PACKAGE / f"{name}.py")
        assert not deps & FORBIDDEN and "shimmy.cli" not in deps, name


def test_every_module_is_assigned_a_layer():
    modules = {p.stem for p in PACKAGE.glob("*.py")} - {"__init__", "__main__", "cli"}
    assert modules == MODEL | ANALYSES


SERVICE = PACKAGE / "service"
ROOT = PACKAGE.parent
#: What the UI may import from the package: definitions and the service layer, never numerics.
UI_MAY_IMPORT = {"shimmy.service", "shimmy.parameters", "shimmy.errors", "shimmy.configurations"}


def _absolute_imports(path):
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            found.add(node.module)
    return found


def test_service_layer_does_not_import_the_ui():
    for path in SERVICE.glob("*.py"):
        deps = imports(path)
        assert not deps & {"dash", "plotly", "ui", "pages", "app"}, path.name


def test_ui_uses_only_the_service_layer_and_definitions():
    files = [ROOT / "app.py", *(ROOT / "pages").glob("*.py"), *(ROOT / "ui").glob("*.py")]
    assert len(files) > 5
    for path in files:
        for name in _absolute_imports(path):
            if name.startswith("shimmy"):
                assert any(name == allowed or name.startswith(allowed + ".") for allowed in UI_MAY_IMPORT), \
                    (path.name, name)
