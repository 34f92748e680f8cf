"""Imports cost what is used: the package, the command line's parser and its help load no compiled
kernel, no sparse algebra and no web or cluster library (each is loaded by the command that needs it)."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

HEAVY = ("numba", "scipy.sparse", "dash", "flask", "distributed")


def modules_loaded_by(*args: str) -> set[str]:
    """Every module a fresh interpreter imports to run ``args`` (from ``python -X importtime``)."""
    done = subprocess.run([sys.executable, "-X", "importtime", *args], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return set(re.findall(r"^import time:\s+\d+ \|\s+\d+ \|\s*([\w.]+)$", done.stderr, re.M))


@pytest.mark.parametrize("args", [("-c", "import shimmy"), ("-m", "shimmy", "--help"),
                                  ("-m", "shimmy", "bifurcation", "--help"), ("-m", "shimmy", "map", "--help")],
                         ids=["import shimmy", "--help", "bifurcation --help", "map --help"])
def test_the_package_and_the_help_load_nothing_heavy(args):
    loaded = modules_loaded_by(*args)
    assert "shimmy" in loaded
    assert not {m for m in loaded if m in HEAVY or m.startswith(tuple(h + "." for h in HEAVY))}


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
