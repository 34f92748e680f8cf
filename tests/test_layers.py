"""The package's folders are its layers, and each imports only downward.

continuation (generic engine) <- model (the gear) <- analyses <- service <- UI (app, pages, ui);
``shimmy.errors`` is the package's exception root, importable from model upwards, and
``shimmy.version`` the ground floor every layer may read. Nothing inside the package imports the
package root (it imports the analyses). The analyses are families, each importing only those below
it: core <- diagrams <- maps, ground <- decisions. The command line (``cli``) is a front door beside
the service: it calls the analyses, reads the service's request schemas and answers from (and fills)
the service's result cache through its analysis registry.
"""

import ast
import pathlib
import sys

import shimmy

PACKAGE = pathlib.Path(shimmy.__file__).parent
ROOT = PACKAGE.parent
LAYERS = ("continuation", "model", "analyses", "service")
TOP_LEVEL = {"__init__", "__main__", "errors", "version"}
#: Folders at the top that are no layer below the others: the command line.
FRONT_DOORS = ("cli",)
UI_LIBRARIES = {"dash", "plotly", "flask", "gunicorn", "diskcache"}
STDLIB = set(sys.stdlib_module_names)


def module_name(path: pathlib.Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_statements(path: pathlib.Path):
    """(module the statement loads, the names it takes, bare) for each import of the file, relative
    imports resolved to absolute dotted names; bare: a relative ``from . import a`` (a: a module)."""
    package = module_name(path) if path.name == "__init__.py" else module_name(path).rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            yield from ((a.name, [], False) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            names = [a.name for a in node.names]
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                yield ".".join(base + ([node.module] if node.module else [])), names, not node.module
            else:
                yield node.module, names, False


def imports(path: pathlib.Path) -> set[str]:
    """Absolute dotted names of every module (or module attribute) the file imports."""
    found = set()
    for module, names, bare in import_statements(path):
        found |= {f"{module}.{name}" for name in names} if bare else {module}
    return found


def files_of(layer: str) -> list[pathlib.Path]:
    files = sorted((PACKAGE / layer).rglob("*.py"))
    assert files, layer
    return files


def imported_modules(path: pathlib.Path) -> set[str]:
    """The modules a file's import statements load (for ``from M import a``: M itself)."""
    return {module for module, _, _ in import_statements(path)}


def shimmy_imports(path: pathlib.Path) -> set[str]:
    return {name for name in imports(path) if name == "shimmy" or name.startswith("shimmy.")}


def within(name: str, *prefixes: str) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def test_resolver_reads_relative_imports():
    assert "shimmy.continuation.core" in imports(PACKAGE / "continuation" / "collocation.py")
    assert "shimmy.model.parameters" in imports(PACKAGE / "analyses" / "core" / "simulation.py")
    assert "shimmy.errors" in imports(PACKAGE / "model" / "parameters.py")


def test_continuation_is_generic_numpy_scipy_and_numba_only():
    """The engine knows nothing of the gear or of the service; numba compiles its condensed LU."""
    for path in files_of("continuation"):
        for name in imports(path):
            if name.startswith("shimmy"):
                assert within(name, "shimmy.continuation"), (path.name, name)
            else:
                assert name.split(".")[0] in STDLIB | {"numpy", "scipy", "numba"}, (path.name, name)


def test_nothing_in_the_package_imports_the_package_root():
    """The root imports the analyses: a module below it that imports the root works only by line order."""
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.parent == PACKAGE and path.stem in ("__init__", "__main__"):
            continue
        assert "shimmy" not in imported_modules(path), path.relative_to(ROOT)


def test_the_version_is_a_ground_floor_module():
    assert imported_modules(PACKAGE / "version.py") == set()
    assert shimmy.__version__ == __import__("shimmy.version").version.__version__


#: Each family of the analyses and the families it may import.
FAMILIES = {"core": set(), "diagrams": {"core"}, "maps": {"core", "diagrams"}, "ground": {"core", "diagrams"},
            "decisions": {"core", "diagrams", "maps"}}


def test_analyses_families_import_only_downward():
    folders = {p.name for p in (PACKAGE / "analyses").iterdir() if p.is_dir() and p.name != "__pycache__"}
    assert folders == set(FAMILIES)
    assert {p.stem for p in (PACKAGE / "analyses").glob("*.py")} == {"__init__"}
    for family, below in FAMILIES.items():
        for path in files_of(f"analyses/{family}"):
            for name in shimmy_imports(path):
                if within(name, "shimmy.analyses"):
                    other = name.split(".")[2]
                    assert other == family or other in below, (family, path.name, name)


def test_model_imports_only_the_model_and_the_errors():
    for path in files_of("model"):
        for name in shimmy_imports(path):
            assert within(name, "shimmy.model", "shimmy.errors", "shimmy.version"), (path.name, name)
        assert not {n.split(".")[0] for n in imports(path)} & UI_LIBRARIES, path.name


def test_analyses_never_import_the_service_the_cli_or_a_ui():
    for path in files_of("analyses"):
        for name in shimmy_imports(path):
            assert not within(name, "shimmy.service", "shimmy.cli"), (path.name, name)
        assert not {n.split(".")[0] for n in imports(path)} & UI_LIBRARIES, path.name


def test_no_private_name_is_imported_across_modules():
    """A leading underscore means "this module's own": another module that needs it gets a public name."""
    files = [*PACKAGE.rglob("*.py"), ROOT / "app.py", *(ROOT / "pages").glob("*.py"), *(ROOT / "ui").rglob("*.py")]
    for path in files:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module != "__future__":
                private = [a.name for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
                assert not private, (path.relative_to(ROOT), node.module, private)


def test_the_service_does_no_numerics():
    """The service validates, caches, queues and serialises; spectra, eigenvalues and sweeps are analyses."""
    for path in files_of("service"):
        tree = ast.parse(path.read_text())
        assert not {n.split(".")[0] for n in imports(path)} & {"scipy", "numba"}, path.name
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "np":
                assert node.attr not in ("fft", "linalg", "hanning", "geomspace", "argmax"), (path.name, node.attr)


def test_service_never_imports_dash_or_the_ui():
    for path in files_of("service"):
        assert not {n.split(".")[0] for n in imports(path)} & {"dash", "plotly", "ui", "pages", "app"}, path.name


def test_every_module_sits_in_a_layer():
    top = {p.stem for p in PACKAGE.glob("*.py")}
    assert top == TOP_LEVEL
    folders = {p.name for p in PACKAGE.iterdir() if p.is_dir() and p.name != "__pycache__"}
    assert folders == set(LAYERS) | set(FRONT_DOORS)
    for layer in LAYERS + FRONT_DOORS:
        assert (PACKAGE / layer / "__init__.py").exists(), layer


#: What the command line may import from the package: the analyses, the model, the errors (the engine's
#: too: its InvalidInputError is bad input) and of the service its request schemas, its analysis registry
#: (whose run_canonical answers from the shared cache), its settings (where that cache is) and the cache
#: itself (``--no-cache`` bypasses it, the nearest cached design included); and, to run the service for a team,
#: its tokens store (``tokens``) and its job queue (``jobs drain``).
CLI_MAY_IMPORT = ("shimmy.cli", "shimmy.analyses", "shimmy.model", "shimmy.errors", "shimmy.continuation.errors",
                  "shimmy.continuation.kinds", "shimmy.service.schemas", "shimmy.service.analyses",
                  "shimmy.service.settings", "shimmy.service.cache", "shimmy.service.tokens",
                  "shimmy.service.jobs", "shimmy.version")


def test_cli_imports_only_the_analyses_the_model_the_errors_and_the_schemas():
    files = files_of("cli")
    assert len(files) > 3
    for path in files:
        for name in shimmy_imports(path):
            assert within(name, *CLI_MAY_IMPORT), (path.name, name)
        assert not {n.split(".")[0] for n in imports(path)} & (UI_LIBRARIES | {"ui", "pages", "app"}), path.name


#: What the UI may import from the package: definitions and the service layer, never numerics.
UI_MAY_IMPORT = ("shimmy.service", "shimmy.errors", "shimmy.version", "shimmy.model.parameters",
                 "shimmy.model.configurations", "shimmy.model.units",  # the units people read: definitions
                 "shimmy.continuation.kinds")  # a definitions module: the special points' kinds, no numerics


def test_ui_uses_only_the_service_layer_and_definitions():
    files = [ROOT / "app.py", *(ROOT / "pages").glob("*.py"), *(ROOT / "ui").rglob("*.py")]
    assert len(files) > 5
    for path in files:
        for name in imports(path):
            if name.startswith("shimmy"):
                assert within(name, *UI_MAY_IMPORT), (path.name, name)


def test_the_engine_exports_what_its_docstring_example_uses():
    """The example in shimmy.continuation's docstring runs and gives the textbook answer."""
    import re

    import numpy as np

    import shimmy.continuation as engine
    code = re.search(r"::\n\n(.*?)\n\n\S", engine.__doc__, re.S).group(1)
    scope: dict = {}
    exec("\n".join(line[4:] for line in code.split("\n")), scope)
    cycles = scope["cycles"]
    assert scope["H"].p == np.float64(scope["H"].p) and abs(scope["H"].p) < 1e-8
    np.testing.assert_allclose(cycles.period, 2 * np.pi, rtol=1e-6)
    big = cycles.p > 0.05
    np.testing.assert_allclose(cycles.x_max[big, 0], np.sqrt(cycles.p[big]), rtol=1e-4)
    assert cycles.stable[big].all()
