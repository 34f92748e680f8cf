"""``python -m shimmy margins``, ``basins`` and ``margin-map``: the JSON the issue asks for, the text, the shared
cache, bad input."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

POINT = ("--config", "original", "--V", "50", "--Fz", "550000")
#: 2 x 2 cells centred on V 60 and 100 m/s, Fz 600 and 800 kN: three bistable, one lateral only.
PLANE = ("--config", "original", "--v-min", "40", "--v-max", "120", "--fz-min", "500000", "--fz-max", "900000",
         "--n-v", "2", "--n-fz", "2")


def run(*args, env=None):
    return subprocess.run([sys.executable, "-m", "shimmy", *args], capture_output=True, text=True, timeout=300,
                          env=env)


def test_margins_json_names_each_attractor_with_its_smallest_kick_and_the_cache_answers_again(tmp_path):
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(tmp_path)}
    out = run("margins", *POINT, "--direction", "psi", "--json", "--progress", "none", env=env)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["cache"] == "miss" and data["direction"] == "psi"
    by_mode = {a["mode"]: a for a in data["attractors"]}
    assert set(by_mode) == {"lateral", "torsional"}
    for a in data["attractors"]:
        assert {"psi", "delta", "lateral"} <= set(a["amplitude"])
        assert {"value", "unit", "direction", "method", "tolerance"} <= set(a["min_disturbance"])
    assert by_mode["lateral"]["standard_start"] and by_mode["lateral"]["min_disturbance"]["value"] == 0.0
    assert 0.0155 < by_mode["torsional"]["min_disturbance"]["value"] < 0.0175
    text = run("margins", *POINT, env=env)
    assert text.returncode == 0 and "smallest psi: 0.01649" in text.stdout and "confirmed" in text.stdout
    assert text.stdout.rstrip().endswith(f"answered from the shared cache ({tmp_path})")


def test_basins_json_counts_every_kick():
    out = run("basins", *POINT, "--samples", "20", "--seed", "2", "--json", "--progress", "none", "--no-cache")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["cache"] == "off"
    assert sum(a["basin"]["count"] for a in data["attractors"]) + data["unsettled"] + data["failed"] == 20
    assert all(a["basin"]["ci95"][0] <= a["basin"]["fraction"] <= a["basin"]["ci95"][1] for a in data["attractors"])


def test_margin_map_json_gives_each_cell_its_margin_and_the_cache_answers_again(tmp_path):
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(tmp_path)}
    out = run("margin-map", *PLANE, "--json", "--progress", "none", env=env)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["cache"] == "miss" and data["direction"] == "psi" and data["unit"] == "rad"
    assert data["V"] == [60.0, 100.0] and data["Fz"] == [600000.0, 800000.0]
    assert [(p["V"], p["Fz"]) for p in data["points"]] == [(60.0, 6e5), (100.0, 6e5), (60.0, 8e5)]
    for p in data["points"]:
        assert {"margin", "tolerance", "lower", "upper", "confirmed", "attractors", "worst"} <= set(p)
        assert p["attractors"][p["worst"]]["mode"] == "torsional" and 0 < p["margin"] < 0.4 and p["confirmed"]
    assert "torsional limit cycle" in data["worst"] and data["counts"]["bistable"] == 3
    text = run("margin-map", *PLANE, env=env)
    assert text.returncode == 0 and "3 cells with two or more attractors (3 Bistable)" in text.stdout
    assert text.stdout.rstrip().endswith(f"answered from the shared cache ({tmp_path})")


@pytest.mark.parametrize("args, needle", [
    (("margins", *POINT, "--direction", "yaw"), "argument --direction: invalid choice: 'yaw'"),
    (("margins", *POINT, "--rtol", "0"), "rtol=0 is out of range; allowed: a number in [0.0001, 0.1]"),
    (("margins", *POINT, "--min-size", "0.05", "--max-size", "0.01"), "min_size=0.05 must be below max_size"),
    (("margins", "--config", "original", "--V", "0", "--Fz", "550000"), "V=0 is out of range"),
    (("basins", *POINT, "--samples", "3"), "samples=3 is out of range; allowed: an integer in [10, 5000]"),
    (("margin-map", "--config", "original", "--n-v", "1"), "n_v=1 is out of range; allowed: an integer in [2, 60]"),
    (("margin-map", "--config", "original", "--fz-min", "500000", "--fz-max", "400000"), "must exceed fz_min"),
    (("margin-map", "--config", "original", "--max-size", "3"), "max_size=3 is out of range"),
])
def test_bad_input_exits_2_naming_the_field(args, needle):
    out = run(*args)
    assert out.returncode == 2 and needle in out.stderr, out.stderr


def test_margins_from_the_standard_starts_cycle_along_a_mix_and_equal_mixes_share_one_cache_entry(tmp_path):
    """``--origin standard_attractor --direction mix --mix``: the kick added to the lateral cycle, along the mix;
    the same mix written otherwise (order, spaces, 0.10 for 0.1) is the same request, answered from the cache."""
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(tmp_path)}
    args = ("margins", *POINT, "--origin", "standard_attractor", "--phases", "2", "--direction", "mix", "--json",
            "--progress", "none")
    out = run(*args, "--mix", "psi=0.01,dpsi=0.1", env=env)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["cache"] == "miss" and data["origin"]["kind"] == "standard_attractor"
    assert data["origin"]["mode"] == "lateral" and data["options"]["mix"] == "psi=0.01,dpsi=0.1"
    torsional = next(a for a in data["attractors"] if a["mode"] == "torsional")["min_disturbance"]
    assert torsional["unit"] == "J" and torsional["mix"] == "psi=0.01,dpsi=0.1" and torsional["check"]["confirmed"]
    assert torsional["disturbance"]["dpsi"] == pytest.approx(10 * torsional["disturbance"]["psi"], rel=1e-12)
    assert 0.0 <= torsional["phase"] < 1.0 and len(torsional["origin_state"]) == 5
    again = run(*args, "--mix", " dpsi = 0.10 , psi=0.01", env=env)
    assert again.returncode == 0 and json.loads(again.stdout)["cache"] == "hit"


@pytest.mark.parametrize("extra, field", [(("--direction", "mix"), "mix"), (("--mix", "psi=1"), "mix"),
                                          (("--direction", "mix", "--mix", "psi=1,yaw=2"), "mix"),
                                          (("--phases", "0"), "phases")])
def test_bad_mix_origin_settings_exit_2_naming_the_field(extra, field):
    out = run("margins", *POINT, *extra, "--no-cache")
    assert out.returncode == 2 and f"{field}=" in out.stderr, out.stderr
