"""The documentation site (docs/) builds with warnings as errors, every reference resolved, and its
generated tables and command lines agree with the code."""

from __future__ import annotations

import html
import re
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from shimmy.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def sphinx(source: Path, out: Path, builder: str = "html") -> subprocess.CompletedProcess:
    """sphinx-build in strict mode: -W (warnings are errors), -n (nitpicky: every reference must
    resolve), -E (no saved environment), --keep-going (report every problem, then fail)."""
    return subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-n", "-E", "-q", "-b", builder,
                           "-d", str(out / ".doctrees"), str(source), str(out)],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    done = sphinx(DOCS, out)  # its time is no test's business (a loaded machine): it is about a minute
    assert done.returncode == 0, f"docs build failed:\n{done.stdout}\n{done.stderr}"
    return out


def _text(page: Path) -> str:
    return re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", page.read_text()))


def test_docs_build_in_strict_mode_with_every_page(site):
    for page in ("index", "model", "numerics", "validation", "http-api", "openapi", "cli", "python-api",
                 "continuation", "tutorials/index", "tutorials/reproduce-study", "tutorials/new-nes-design",
                 "tutorials/dask-map", "tutorials/ground-runs", "tutorials/design-sessions",
                 "tutorials/design-decisions", "tutorials/disturbance-margins"):
        assert (site / f"{page}.html").is_file(), page


def test_generated_tables_come_from_the_code(site):
    from shimmy.model.parameters import PARAMETER_SPECS
    from shimmy.service import schemas
    from shimmy.service.api import PREFIX, openapi_document

    model = _text(site / "model.html")
    for spec in PARAMETER_SPECS.values():
        assert f"{spec.low:g} to {spec.high:g}" in model and spec.description in model, spec.name
    api = _text(site / "http-api.html")
    for path, item in openapi_document()["paths"].items():
        for method in item:
            if method != "parameters":
                assert f"{method.upper()} {PREFIX}{path}" in api, (method, path)
    for schema in schemas.SCHEMAS.values():
        for f in schema.fields:
            assert f.allowed in html.unescape(api), (schema.name, f.name)  # the page escapes <, >, @
    from shimmy.analyses.ground.ground_profiles import PRESETS, preset_fields

    numerics = _text(site / "numerics.html")
    for name in PRESETS:
        for f in preset_fields(name):
            assert f"{f['low']:g} to {f['high']:g}" in numerics and f["description"] in numerics, (name, f["name"])
    cli = _text(site / "cli.html")
    sub = next(a for a in build_parser()._actions if hasattr(a, "choices") and isinstance(a.choices, dict))
    for command in sub.choices:
        assert f"python -m shimmy {command}" in cli, command


def test_python_api_documents_every_public_name(site):
    import shimmy
    import shimmy.continuation

    for module, page in ((shimmy, "python-api.html"), (shimmy.continuation, "continuation.html")):
        html = (site / page).read_text()
        missing = [name for name in module.__all__ if f'id="{module.__name__}.{name}"' not in html]
        assert not missing, f"{module.__name__}: {missing}"


def test_nothing_points_to_the_specification_folder_a_clone_does_not_have():
    outside = "/".join(("shared", "spec"))  # joined, so that this file does not mention it either
    tracked = subprocess.run(["git", "ls-files"], capture_output=True, text=True, cwd=ROOT).stdout.split()
    paths = [ROOT / p for p in tracked] or [*DOCS.rglob("*.md"), ROOT / "README.md", *(ROOT / "pages").glob("*.py")]
    for path in paths:
        if path.is_file() and path.suffix in (".md", ".py", ".toml", ".yaml", ".txt", ".sh", ""):
            assert outside not in path.read_text(errors="replace"), path


def test_a_broken_link_and_a_broken_reference_fail_the_build(tmp_path):
    """The docs' own configuration (conf.py, its extension, its static files) on a one-page tree: the page
    builds cleanly as it is, and a link to a page that does not exist and a reference to a function that does
    not exist each fail the strict build, named (a one-page tree: the whole site's build is the fixture's)."""
    def tree(name: str, text: str) -> Path:
        source = tmp_path / name / "docs"  # conf.py finds its extension at ../docs/_ext
        source.mkdir(parents=True)
        shutil.copy(DOCS / "conf.py", source)
        for folder in ("_ext", "_static"):
            shutil.copytree(DOCS / folder, source / folder)
        (source / "index.md").write_text(f"# One page\n\nSee [this page](index.md).\n{text}")
        return source

    clean = sphinx(tree("clean", ""), tmp_path / "clean-out", "dummy")
    assert clean.returncode == 0, clean.stderr
    broken = "\nSee [the model](no-such-page.md) and {py:func}`shimmy.no_such_function`.\n"
    done = sphinx(tree("broken", broken), tmp_path / "out", "dummy")
    assert done.returncode != 0
    assert "no-such-page.md" in done.stderr and "shimmy.no_such_function" in done.stderr, done.stderr


def _documented_commands() -> list[tuple[str, str]]:
    """Every `python -m shimmy ...` command in the docs' code blocks (bash lines, or `$ ` lines)."""
    found = []
    for page in DOCS.rglob("*.md"):
        for block in re.findall(r"```(?:bash|text)\n(.*?)```", page.read_text(), flags=re.S):
            for line in block.replace("\\\n", " ").splitlines():
                line = line.strip().removeprefix("$ ")
                line = re.sub(r"^(\w+=\S+ )+", "", line)  # environment assignments
                if line.startswith("python -m shimmy "):
                    command = line.split(" > ")[0].split(" | ")[0].split("  #")[0]
                    found.append((page.relative_to(DOCS).as_posix(), command))
    return found


def test_the_docs_show_commands():
    pages = {page for page, _ in _documented_commands()}
    assert {"tutorials/reproduce-study.md", "tutorials/new-nes-design.md", "tutorials/dask-map.md",
            "tutorials/ground-runs.md", "tutorials/design-decisions.md", "tutorials/disturbance-margins.md"} <= pages


@pytest.mark.parametrize("page,command", _documented_commands(),
                         ids=[f"{page}:{k}" for k, (page, _) in enumerate(_documented_commands())])
def test_every_documented_command_line_parses(page, command):
    args = shlex.split(command)[3:]
    try:
        build_parser().parse_args(args)
    except SystemExit:
        pytest.fail(f"{page}: {command!r} is not a valid command line")


def _examples_with_output() -> list[tuple[str, str, str]]:
    """(page, code, printed output) of every ```python block followed directly by a ```text block
    on the tutorial pages whose output does not depend on timing (the Dask page's does)."""
    found = []
    for name in ("tutorials/reproduce-study.md", "tutorials/new-nes-design.md", "tutorials/ground-runs.md",
                 "tutorials/disturbance-margins.md"):
        text = (DOCS / name).read_text()
        for code, output in re.findall(r"```python\n(.*?)```\n\n```text\n(.*?)```", text, flags=re.S):
            found.append((name, code, output))
    return found


def test_the_tutorials_show_python_examples():
    assert {page for page, _, _ in _examples_with_output()} == {"tutorials/reproduce-study.md",
                                                                "tutorials/new-nes-design.md",
                                                                "tutorials/ground-runs.md",
                                                                "tutorials/disturbance-margins.md"}


@pytest.mark.slow
@pytest.mark.parametrize("page,code,output", _examples_with_output(),
                         ids=[f"{page}:{k}" for k, (page, _, _) in enumerate(_examples_with_output())])
def test_tutorial_examples_print_what_the_page_shows(page, code, output):
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert done.stdout == output, f"{page}: the example now prints\n{done.stdout}"


def test_the_tests_and_files_the_docs_cite_exist():
    pages = "\n".join(page.read_text() for page in DOCS.rglob("*.md"))
    cited_tests = set(re.findall(r"`(?:tests/\w+\.py::)?(test_\w+)`", pages))
    defined = set(re.findall(r"def (test_\w+)", "\n".join(p.read_text() for p in (ROOT / "tests").rglob("*.py"))))
    assert cited_tests and not cited_tests - defined, sorted(cited_tests - defined)
    cited_files = set(re.findall(r"`((?:tests|shimmy|scripts|benchmarks|docs)/[\w/.-]+\.(?:py|sh|md))", pages))
    assert cited_files and not [f for f in cited_files if not (ROOT / f).is_file()]
    for name in re.findall(r"`((?:compose|gunicorn)[\w.]*\.(?:yaml|py))`", pages):
        assert (ROOT / name).is_file(), name


def _readme_commands() -> list[str]:
    """The lines of the README's bash blocks, in order."""
    text = (ROOT / "README.md").read_text()
    return [line.strip() for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S)
            for line in block.splitlines() if line.strip()]


def test_the_readme_starts_in_a_virtual_environment_with_the_two_commands():
    """A new user's first lines: a virtual environment, the workbench's command, then the tests' command, which
    is the one CI runs (.ci/run)."""
    first = _readme_commands()[:3]
    assert first[0] == "python3.11 -m venv .venv && . .venv/bin/activate"
    assert first[1].startswith('python -m pip install -e ".[web]" && python -m gunicorn app:server ')
    ci = [line for line in (ROOT / ".ci" / "run").read_text().splitlines() if line.startswith("python -m pip")]
    assert first[2] == ci[0]


def test_the_readme_ends_its_first_screen_with_a_five_minute_tour():
    """The tour is within the README's first screen (50 lines) and walks Overview, a drag of e_p, Bifurcation,
    the Stability map and a click on a point, in that order."""
    screen = "\n".join((ROOT / "README.md").read_text().splitlines()[:50])
    assert "**A five-minute tour**" in screen
    tour = screen[screen.index("**A five-minute tour**"):]
    steps = re.findall(r"^\d\. \*\*(.+?)\*\*", tour, flags=re.M)
    assert steps == ["Overview", "Drag e_p", "Bifurcation", "Stability map", "Click a point"]
