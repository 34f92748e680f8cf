"""Imports cost what is used: the package, the command line's parser and its help, and an answer the
command line reads from the shared cache load no compiled kernel, no sparse algebra and no web or
cluster library (each is loaded by the command that needs it)."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import pytest

HEAVY = ("numba", "scipy.sparse", "dash", "flask", "distributed")
SMALL_MAP = ("map", "--config", "original", "--fz-min", "300000", "--fz-max", "400000", "--resolution", "2",
             "--n-v", "10", "--progress", "none")


def modules_loaded_by(*args: str, env: dict[str, str] | None = None) -> set[str]:
    """Every module a fresh interpreter imports to run ``args`` (from ``python -X importtime``)."""
    done = subprocess.run([sys.executable, "-X", "importtime", *args], capture_output=True, text=True, timeout=600,
                          env=env)
    assert done.returncode == 0, done.stderr[-2000:]
    return set(re.findall(r"^import time:\s+\d+ \|\s+\d+ \|\s*([\w.]+)$", done.stderr, re.M))


def heavy(loaded: set[str]) -> set[str]:
    return {m for m in loaded if m in HEAVY or m.startswith(tuple(h + "." for h in HEAVY))}


@pytest.mark.parametrize("args", [("-c", "import shimmy"), ("-m", "shimmy", "--help"),
                                  ("-m", "shimmy", "bifurcation", "--help"), ("-m", "shimmy", "map", "--help")],
                         ids=["import shimmy", "--help", "bifurcation --help", "map --help"])
def test_the_package_and_the_help_load_nothing_heavy(args):
    loaded = modules_loaded_by(*args)
    assert "shimmy" in loaded
    assert not heavy(loaded)


@pytest.fixture(scope="module")
def cache_with_a_map(tmp_path_factory) -> dict[str, str]:
    """The environment of a fresh cache holding SMALL_MAP, which computing it loaded the kernels for."""
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(tmp_path_factory.mktemp("map-cache"))}
    assert "numba" in modules_loaded_by("-m", "shimmy", *SMALL_MAP, env=env)
    return env


@pytest.mark.parametrize("output", [(), ("--json",), ("--csv", "{tmp}/map.csv")], ids=["text", "json", "csv"])
def test_a_cached_map_answer_loads_nothing_heavy(cache_with_a_map, tmp_path, output):
    output = tuple(o.replace("{tmp}", str(tmp_path)) for o in output)
    loaded = modules_loaded_by("-m", "shimmy", *SMALL_MAP, *output, env=cache_with_a_map)
    assert "shimmy.cli.answers" in loaded and "diskcache" in loaded
    assert not heavy(loaded)
    done = subprocess.run([sys.executable, "-m", "shimmy", *SMALL_MAP, "--json"], capture_output=True, text=True,
                          timeout=120, env=cache_with_a_map)
    assert json.loads(done.stdout)["cache"] == "hit"


def test_the_check_sees_a_heavy_import():
    """The same check on a command that computes: it does load the compiled kernels."""
    loaded = modules_loaded_by("-c", "import shimmy; shimmy.simulate")
    assert "numba" in loaded


def test_the_lazy_names_are_the_package_s_names():
    import shimmy
    import shimmy.continuation as engine

    assert set(shimmy.__all__) <= set(dir(shimmy)) and set(engine.__all__) <= set(dir(engine))
    assert shimmy.simulate.__module__ == "shimmy.analyses.core.simulation"
    assert engine.periodic_branch.__module__ == "shimmy.continuation.periodic_orbits"
    with pytest.raises(AttributeError, match="no attribute 'simulated'"):
        shimmy.simulated  # noqa: B018
