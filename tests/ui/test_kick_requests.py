"""The Time history page's run from a margin's kick (pages/time_history.py, no browser): the whole state ``x0`` is
asked for only while the point, the design and the psi0 / l_g delta0 boxes are as the kick's Run left them."""

from __future__ import annotations

import pytest

from shimmy.service import schemas

X0 = [0.2369, -1.496, 0.02936, -1.642, 0.005375]


@pytest.fixture(scope="module")
def page():
    import app  # noqa: F401 - registers the pages
    from pages import time_history

    return time_history


def _kick(design):
    return {"attractor": 1, "clicks": 1, "x0": X0, "psi0": 0.2369, "lateral0": 73.4,
            "point": ["original", 50.0, 550e3], "design": schemas.design(design["params"], design["material"])}


def _ask(page, kick, design, V=50, psi0=0.2369, lateral0=73.4, config="original"):
    return page._requests(V, 550, None, kick, config, 80, psi0, lateral0, "cubic", None, design)


@pytest.mark.parametrize("change, from_kick", [
    ({}, True), ({"V": 51}, False), ({"psi0": 0.2}, False), ({"lateral0": 70.0}, False), ({"config": "nes"}, False),
    ({"design": {"material": None, "params": {"r2": 0.085}}}, False),
    ({"design": {"material": "tungsten", "params": {}}}, False),
])
def test_the_kicks_state_is_asked_only_while_point_design_and_boxes_are_the_kicks(page, change, from_kick):
    design = {"material": None, "params": {}}
    kick = _kick(design)
    asked = _ask(page, kick, **{"design": design, **change})
    assert len(asked) == 1
    assert ("x0" in asked[0]) is from_kick
    if from_kick:
        assert asked[0]["x0"] == X0 and "psi0" not in asked[0]
    else:
        assert asked[0]["psi0"] == pytest.approx(change.get("psi0", 0.2369))
