import csv
import json
import subprocess
import sys

import pytest

from shimmy.model.parameters import PARAMETER_SPECS


def run(*args):
    return subprocess.run([sys.executable, "-m", "shimmy", *args], capture_output=True, text=True, timeout=120)


def test_params_lists_every_parameter():
    out = run("params", "--json")
    assert out.returncode == 0
    rows = json.loads(out.stdout)["parameters"]
    assert [r["name"] for r in rows] == list(PARAMETER_SPECS)
    assert {"name", "unit", "default", "low", "high", "description"} <= set(rows[0])
    text = run("params")
    assert "k_lam" in text.stdout and "concave-track radius" in text.stdout


def test_hopf_json():
    out = run("hopf", "--config", "nes", "--Fz", "150000", "--json", "--set", "e_p=0.001")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["config"] == "nes" and data["Fz"] == 150000.0 and data["params"]["e_p"] == 0.001
    speeds = [h["V"] for h in data["hopf_points"]]
    assert speeds == pytest.approx([6.730, 71.255], rel=2e-3)
    assert {h["criticality"] for h in data["hopf_points"]} == {"supercritical"}


def test_simulate_json_and_csv(tmp_path):
    path = tmp_path / "a.csv"
    out = run("simulate", "--config", "nes_pd", "--V", "30", "--Fz", "150000", "--t-end", "20",
              "--json", "--csv", str(path))
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert set(data["amplitude"]) >= {"psi", "lateral"}
    assert data["response_type"] == "Torsion" and 10 < data["frequency_hz"] < 13
    assert data["params"]["g_p"] == PARAMETER_SPECS["g_p"].default
    with open(path) as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["t", "psi", "dpsi", "delta", "ddelta", "lam", "psis", "dpsis", "lateral"]
    assert len(rows) == 20001 + 1


@pytest.mark.parametrize("args,needle", [
    (["hopf", "--config", "nes", "--Fz", "1e9"],
     "Fz=1e9 is out of range; allowed: a number in [10000, 900000] N"),
    (["hopf", "--config", "nes", "--Fz", "150000", "--set", "r2=0.2"], "r2=0.2 is out of range"),
    (["hopf", "--config", "nes", "--Fz", "150000", "--set", "zeta=1"], "unknown parameter 'zeta'"),
    (["hopf", "--config", "nes", "--Fz", "150000", "--set", "r2"], "--set='r2' is not of the form NAME=VALUE"),
    (["simulate", "--config", "pd", "--V", "fast", "--Fz", "150000"], "V='fast' is not a number"),
    (["simulate", "--config", "pd", "--V", "30", "--Fz", "nan"], "Fz=nan is not finite"),
    (["simulate", "--config", "pd", "--V", "30", "--Fz", "150000", "--t-end", "1e9"],
     "t_end=1e9 is out of range"),
    (["simulate", "--config", "gear", "--V", "30", "--Fz", "150000"], "argument --config: invalid choice"),
])
def test_bad_input_exits_2_naming_the_field(args, needle):
    out = run(*args)
    assert out.returncode == 2
    assert needle in out.stderr
    assert out.stdout == ""


def test_eigen_json_matches_the_library():
    from shimmy.analyses.core.stability import eigenvalues

    out = run("eigen", "--config", "pd", "--V", "30", "--Fz", "150000", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    ev = eigenvalues("pd", 30.0, 150e3)
    assert [e["real"] for e in data["eigenvalues"]] == pytest.approx(ev.real.tolist())
    assert data["stable"] is False  # point A lies between the Hopf points


def test_progress_is_a_bar_on_a_terminal_and_plain_lines_elsewhere():
    import io

    from shimmy.cli.common import ProgressBar as _ProgressBar

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    tty, pipe, quiet = Terminal(), io.StringIO(), io.StringIO()
    for stream, mode in ((tty, "auto"), (pipe, "auto"), (quiet, "none")):
        bar = _ProgressBar(stream, width=10, mode=mode)
        bar(0.5, "periodic branch")
        bar(0.51, "periodic branch")  # same message, under 5 % further: no new line
        bar(1.0, "done")
        bar.close()
    assert "[#####.....]  50.0 % periodic branch" in tty.getvalue()
    assert "[##########] 100.0 % done" in tty.getvalue()
    assert pipe.getvalue() == "[ 50.0 %] periodic branch\n[100.0 %] done\n"
    assert quiet.getvalue() == ""


def test_map_without_a_terminal_logs_its_progress_counting_the_slices_asked():
    out = run("map", "--config", "original", "--fz-min", "100000", "--fz-max", "400000", "--resolution", "3",
              "--n-v", "20", "--json", "--no-cache")  # computed, whatever the session's cache holds
    assert out.returncode == 0, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) >= 4 and all(line.startswith("[") and " %] " in line for line in lines)
    assert lines[-1].startswith("[100.0 %]") and "\r" not in out.stderr
    assert "1/3 slices" in out.stderr  # counted in the slices asked for (more follow through regions they miss)


def test_help_is_complete_plain_text_and_shows_the_shared_limits():
    top = run("--help")
    assert top.returncode == 0 and "``" not in top.stdout and "Units are SI" in top.stdout
    assert "map --config nes_pd --resolution 10" in top.stdout
    for command in ("map", "simulate", "study", "bifurcation"):
        text = run(command, "--help").stdout
        assert "``" not in text and "--progress" in text or command == "simulate"
    assert "(2 to 80)" in run("map", "--help").stdout  # the API's limits, from its schema
    assert "(0.1 to 600 s)" in run("simulate", "--help").stdout


@pytest.mark.parametrize("argv, needle", [
    (["map", "--config", "nes", "--resolution", "81"],
     "resolution=81 is out of range; allowed: an integer in [2, 80]"),
    (["simulate", "--config", "nes", "--V", "30", "--Fz", "150000", "--t-end", "601"],
     "t_end=601 is out of range; allowed: a number in [0.1, 600] s"),
    (["bifurcation", "--config", "nes", "--Fz", "150000", "--ntst", "5"], "ntst"),
])
def test_cli_limits_are_the_apis(argv, needle):
    from shimmy.service import schemas

    assert schemas.SCHEMAS["map"].field("resolution").high == 80
    out = run(*argv)
    assert out.returncode == 2 and needle in out.stderr


def test_hopf_curves_command(capsys):
    from shimmy.cli import main

    assert main(["hopf-curves", "--config", "original", "--fz-min", "300000", "--fz-max", "500000",
                 "--v-max", "200", "--json"]) == 0
    import json

    d = json.loads(capsys.readouterr().out)
    assert d["config"] == "original" and d["curves"]
    # End points are located on the box edges to 1e-9 relative.
    assert all(300000 - 1e-3 <= p["Fz"] <= 500000 + 1e-3 and 1 - 1e-9 <= p["V"] <= 200 + 1e-9
               for c in d["curves"] for p in c["points"])
    assert main(["hopf-curves", "--config", "original", "--fz-min", "5e5", "--fz-max", "1e5"]) == 2


def test_map_command_json_carries_the_curves_grid_and_minimum_load(tmp_path):
    path = tmp_path / "map.csv"
    out = run("map", "--config", "original", "--v-min", "1", "--v-max", "200", "--fz-min", "100000",
              "--fz-max", "450000", "--resolution", "4", "--n-v", "25", "--json", "--csv", str(path))
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    for key in ("hopf_curves", "fold_curves", "torus_curves"):
        assert all(set(p) >= {"V", "Fz"} for c in data[key] for p in c), key
    assert data["hopf_curves"] and data["gh_points"] and data["torus_curves"]
    # the 4 slices asked, and those the map adds through regions between the curves they miss
    asked = [100000.0 + k * 350000.0 / 3 for k in range(4)]
    assert all(min(abs(f - a) for f in data["Fz"]) < 1e-6 for a in asked)
    assert len(data["types"]) == len(data["Fz"]) >= 4 and len(data["V"]) == 25
    assert all(len(row) == 25 for row in data["types"])
    shading = data["shading"]
    assert len(shading["Fz"]) >= 180 and all(len(row) == 25 for row in shading["types"])
    types = {"Stable", "Torsion", "Lateral", "Bistable", "Both", "Latent"}
    assert data["regions"] and {r["type"] for r in data["regions"]} <= types
    assert data["min_shimmy_Fz"] == pytest.approx(100000.0)  # shimmy on the lowest slice already
    assert data["metrics"]["torsion_area"] > 0
    assert "two-parameter continuation" in data["methods"]["hopf_curves"]
    assert "two-parameter continuation" in data["methods"]["fold_curves"]
    assert "double_hopf_points" in data
    rows = list(csv.reader(path.open()))
    assert rows[0] == ["Fz_N", "V_m_s", "shimmy_type"] and len(rows) == 1 + len(shading["Fz"]) * 25  # the shading


def test_classify_command():
    out = run("classify", "--config", "original", "--V", "50", "--Fz", "350000", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["shimmy_type"] == "Bistable"
    assert sorted(a["mode"] for a in data["attractors"]) == ["lateral", "torsional"]


def test_study_command_json_and_csv():
    out = run("study", "--param", "e_p", "--values", "0.0005,0.001,0.005", "--configs", "nes,nes_pd",
              "--Fz", "150000", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert len(data["rows"]) == 6 and data["values"] == [[0.0005, 0.001, 0.005]]
    row = next(r for r in data["rows"] if r["e_p"] == 0.001 and r["config"] == "nes")
    assert [row["hopf_start"], row["hopf_end"]] == pytest.approx([6.730, 71.255], rel=2e-3)
    out = run("study", "--param", "e_p", "--values", "0.001", "--configs", "nes", "--csv")
    rows = list(csv.reader(out.stdout.splitlines()))
    assert rows[0][:3] == ["e_p", "config", "hopf_start_m_s"] and rows[1][:2] == ["0.001", "nes"]


@pytest.mark.parametrize("args, needle", [
    (["study", "--param", "e_q", "--values", "1"], "parameter"),
    (["study", "--param", "e_p", "--values", "0.5"], "e_p"),
    (["study", "--param", "e_p", "--values", "a,b"], "values"),
    (["study", "--param", "e_p", "--values", "0.001", "--configs", "nes,foo"], "config"),
    (["map", "--config", "nes", "--resolution", "1"], "resolution"),
    (["map", "--config", "nes", "--fz-min", "5e5", "--fz-max", "1e5"], "fz_max"),
    (["classify", "--config", "nes", "--V", "300", "--Fz", "150000"], "V"),
])
def test_bad_map_study_classify_input_exits_2_naming_the_field(args, needle):
    out = run(*args)
    assert out.returncode == 2, (out.returncode, out.stderr)
    assert needle in out.stderr


def test_sensitivity_optimise_robustness_commands_give_the_documented_json():
    out = run("sensitivity", "--config", "nes", "--Fz", "150000", "--no-amplitude", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert len(data["hopf_points"]) == 2 and set(data["hopf_points"][0]["dV_dp"]) == set(PARAMETER_SPECS)
    assert {"Fz", "dFz_dp"} <= set(data["min_shimmy_Fz"])
    assert "a_p" in data["no_effect"]["hopf"]
    text = run("sensitivity", "--config", "pd", "--Fz", "150000", "--no-amplitude")
    assert "zero at rest" in text.stdout and "per +1 %" in text.stdout
    out = run("optimise", "--config", "nes", "--params", "e_p", "--starts", "2", "--local-runs", "1", "--json",
              "--progress", "none")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert {"design", "objective", "nominal_objective", "evaluations"} <= set(data)
    assert data["objective"] >= data["nominal_objective"] and set(data["design"]) == {"e_p"}
    out = run("robustness", "--config", "nes_pd", "--tolerance", "k_lam=0.05", "--tolerance", "k_s=0.05",
              "--samples", "16", "--json", "--progress", "none")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert {"mean", "std", "p05", "p95", "linear_std"} <= set(data["hopf_points"][0])
    assert set(data["p_shimmy"]) == set("ABCDEFGHI")


@pytest.mark.parametrize("args, needle", [
    (("sensitivity", "--config", "nes", "--Fz", "1"), "Fz"),
    (("sensitivity", "--config", "nes", "--params", "k_sx"), "k_sx"),
    (("optimise", "--config", "nes", "--constraint", "max_psi<0.02"), "constraint"),
    (("optimise", "--config", "original", "--params", "k_s"), "is not a parameter of configuration original"),
    (("optimise", "--config", "original"), "it has no device"),
    (("robustness", "--config", "nes", "--tolerance", "k_s=2"), "tolerances[0].relative=2.0 is out of range"),
    (("robustness", "--config", "nes"), "tolerance"),
    (("robustness", "--config", "nes", "--tolerance", "k_s=0.05", "--disturbance", "0.0010"),
     "disturbance=0.0010 is out of range; allowed: a number in [0.002, 1] rad"),
    (("robustness", "--config", "nes", "--tolerance", "k_s=0.05", "--disturbance", "0.1", "--samples", "300"),
     "samples=300 asks for too many samples with a disturbance"),
    (("ground-run", "--config", "nes", "--profile", "takeoff", "--kick", "psi", "--kick-size", "0.80",
      "--kick-at-time", "3"), "kick_size=0.80 is out of range; allowed: a number in [-0.5, 0.5] rad"),
    (("ground-run", "--config", "nes", "--profile", "landing", "--kick", "dpsi", "--kick-size", "2",
      "--kick-at-speed", "70"), "kick_at_speed=70 m/s is never reached by the landing profile"),
])
def test_bad_design_command_input_exits_2_naming_the_field(args, needle):
    out = run(*args)
    assert out.returncode == 2, out.stdout + out.stderr
    assert needle in out.stderr


def test_simulate_takes_the_start_state_as_the_api_does(tmp_path):
    """--psi0 and --lateral0 (the API's psi0 and lateral0): a yaw kick above original's margin at
    (50 m/s, 550 kN), about 0.0165 rad, ends in torsional shimmy; the standard start, in lateral."""
    def run_json(*extra):
        out = subprocess.run([sys.executable, "-m", "shimmy", "simulate", "--config", "original", "--V", "50",
                              "--Fz", "550000", "--t-end", "40", "--json", "--no-cache", *extra],
                             capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr[-2000:]
        return json.loads(out.stdout)

    kicked, standard = run_json("--psi0", "0.03"), run_json()
    assert kicked["start"] == {"psi0": 0.03, "lateral0": 0.0} and kicked["response_type"] == "Torsion"
    assert standard["start"] == {"psi0": 0.001, "lateral0": 0.0} and standard["response_type"] == "Lateral"
    csv_path = tmp_path / "kick.csv"
    out = subprocess.run([sys.executable, "-m", "shimmy", "simulate", "--config", "original", "--V", "50", "--Fz",
                          "550000", "--t-end", "1", "--psi0", "0.03", "--lateral0", "0.01", "--csv", str(csv_path)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    first = csv_path.read_text().splitlines()[1].split(",")
    assert float(first[1]) == pytest.approx(0.03) and float(first[-1]) == pytest.approx(0.01)  # psi, lateral at t = 0
