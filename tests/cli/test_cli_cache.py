"""The command line on the service's shared result cache: a question answered by the API (in the request or
as a job) is answered by the CLI from the cache without computing, and the other way round; a cached answer
prints exactly what a computed one does; ``--no-cache`` neither reads nor writes the cache.

The API is a real gunicorn (the ``server`` fixture of tests/conftest.py); the command line is run as a
process with ``SHIMMY_CACHE_DIR`` set to that server's cache directory.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time

import diskcache
import pytest

#: What computing loads and a cached answer must not (the compiled kernels, the sparse solvers).
NUMERICS = ("numba", "scipy.sparse")
SMALL_MAP = ["--config", "original", "--fz-min", "300000", "--fz-max", "400000", "--resolution", "2", "--n-v", "10"]
SMALL_MAP_BODY = {"config": "original", "fz_min": 300000, "fz_max": 400000, "resolution": 2, "n_v": 10}


def shimmy(cache_dir, *args: str, importtime: bool = False) -> tuple[subprocess.CompletedProcess, set[str]]:
    """``python -m shimmy ARGS`` on the cache in ``cache_dir``: (the process, the modules it imported)."""
    flags = ["-X", "importtime"] if importtime else []
    done = subprocess.run([sys.executable, *flags, "-m", "shimmy", *args], capture_output=True, text=True,
                          timeout=600, env={**os.environ, "SHIMMY_CACHE_DIR": str(cache_dir)})
    loaded = set(re.findall(r"^import time:\s+\d+ \|\s+\d+ \|\s*([\w.]+)$", done.stderr, re.M))
    return done, loaded


def computed(loaded: set[str]) -> bool:
    """Whether a process loaded the numerics (a cached answer does not: it only reads and prints)."""
    return any(m in NUMERICS or m.startswith(tuple(n + "." for n in NUMERICS)) for m in loaded)


def entries(cache_dir) -> int:
    with diskcache.Cache(str(cache_dir / "results")) as store:
        return sum(1 for k in store.iterkeys() if not str(k).startswith("__"))


def without_cache_line(text: str) -> tuple[str, str]:
    """(the text without its last line, that line)."""
    body, _, last = text.rstrip("\n").rpartition("\n")
    return body, last


def test_the_same_request_through_the_api_and_then_the_cli_computes_once(server):
    body = {"config": "pd", "Fz": 200000, "params": {"r2": 0.085}, "material": "tungsten"}
    status, headers, api = server.request("POST", "/api/v1/hopf", body)
    assert status == 200 and headers["X-Shimmy-Cache"] == "miss"
    stored = entries(server.cache_dir)
    out, loaded = shimmy(server.cache_dir, "hopf", "--config", "pd", "--Fz", "200000", "--set", "r2=0.085",
                         "--material", "tungsten", "--json", importtime=True)
    assert out.returncode == 0, out.stderr[-2000:]
    cli = json.loads(out.stdout)
    assert cli.pop("cache") == "hit" and cli == api  # the API's result, key for key
    assert not computed(loaded) and entries(server.cache_dir) == stored
    text, _ = shimmy(server.cache_dir, "hopf", "--config", "pd", "--Fz", "200000", "--set", "r2=0.085",
                     "--material", "tungsten")
    assert text.stdout.rstrip().endswith(f"answered from the shared cache ({server.cache_dir})")


def test_a_map_job_of_the_api_is_the_cli_s_cached_map(server):
    status, _, job = server.request("POST", "/api/v1/jobs", {"analysis": "map", **SMALL_MAP_BODY})
    assert status == 202
    deadline = time.time() + 600
    while job["status"] not in ("done", "failed", "cancelled") and time.time() < deadline:
        time.sleep(0.5)
        _, _, job = server.request("GET", f"/api/v1/jobs/{job['id']}")
    assert job["status"] == "done", job
    stored = entries(server.cache_dir)
    out, loaded = shimmy(server.cache_dir, "map", *SMALL_MAP, "--json", importtime=True)
    assert out.returncode == 0, out.stderr[-2000:]
    cli = json.loads(out.stdout)
    assert cli.pop("cache") == "hit" and cli == job["result"]
    assert not computed(loaded) and entries(server.cache_dir) == stored
    assert not {m for m in loaded if m in ("dash", "flask", "distributed") or m.startswith(("dash.", "flask."))}


def test_a_question_the_cli_answered_is_answered_by_the_api_from_the_cache(server):
    out, loaded = shimmy(server.cache_dir, "simulate", "--config", "nes", "--V", "45", "--Fz", "300000",
                         "--t-end", "5", "--json", importtime=True)
    assert out.returncode == 0, out.stderr[-2000:]
    cli = json.loads(out.stdout)
    assert cli.pop("cache") == "miss" and computed(loaded)
    status, headers, api = server.request("POST", "/api/v1/simulate",
                                          {"config": "nes", "V": 45, "Fz": 300000, "t_end": 5})
    assert status == 200 and headers["X-Shimmy-Cache"] == "hit"
    assert api["start"] == {"psi0": 0.001, "lateral0": 0.0}  # the standard start, the CLI's default too
    assert api == cli  # the start included: the CLI takes --psi0 and --lateral0 as the API does


@pytest.mark.parametrize("args, csv", [
    (["bifurcation", "--config", "original", "--Fz", "150000", "--progress", "none"], True),
    (["ground-run", "--config", "nes", "--profile", "landing"], True),
    (["ground-run", "--config", "all", "--profile", "taxi", "--profile-set", "duration=40"], False),
    (["study", "--param", "e_p", "--values", "0.001,0.004", "--configs", "nes", "--progress", "none"], False),
    (["devices", "--v-max", "3"], False),
], ids=["bifurcation", "ground-run", "ground-run all", "study", "devices"])
def test_a_cached_answer_prints_what_the_computed_one_did(tmp_path, args, csv):
    """Computed (miss), then from the cache (hit): the same JSON but for "cache", the same CSV, and (on another
    cache) the same text but for its last line; the first run stored what the second read, computing nothing."""
    json_cache, text_cache = tmp_path / "json", tmp_path / "text"
    runs = []
    for attempt in ("miss", "hit"):
        files = ["--csv", str(tmp_path / f"{attempt}.csv")] if csv else []
        out, loaded = shimmy(json_cache, *args, *files, "--json", importtime=True)
        assert out.returncode == 0, out.stderr[-2000:]
        text, _ = shimmy(text_cache, *args)
        assert text.returncode == 0, text.stderr[-2000:]
        runs.append((json.loads(out.stdout), without_cache_line(text.stdout),
                     (tmp_path / f"{attempt}.csv").read_text() if csv else None, computed(loaded), entries(json_cache)))
    (miss, miss_text, miss_csv, miss_computed, stored), (hit, hit_text, hit_csv, hit_computed, still) = runs
    assert miss.pop("cache") == "miss" and hit.pop("cache") == "hit"
    assert json.dumps(hit) == json.dumps(miss)  # key order too
    assert hit_csv == miss_csv
    assert miss_text[1] == f"computed and stored in the shared cache ({text_cache})"
    assert hit_text[1] == f"answered from the shared cache ({text_cache})"
    assert hit_text[0] == miss_text[0] != ""
    assert miss_computed and not hit_computed and still == stored >= 1


def test_ground_run_all_says_how_many_runs_came_from_the_cache(tmp_path):
    cache = tmp_path / "cache"
    taxi = ["--profile", "taxi", "--profile-set", "duration=40"]
    assert shimmy(cache, "ground-run", "--config", "nes", *taxi)[0].returncode == 0
    out, _ = shimmy(cache, "ground-run", "--config", "all", *taxi)
    assert out.returncode == 0, out.stderr
    assert without_cache_line(out.stdout)[1] == (f"1 of 4 answered from the shared cache ({cache}), the others "
                                                 "computed and stored there")
    out, _ = shimmy(cache, "ground-run", "--config", "all", *taxi, "--json")
    assert json.loads(out.stdout)["cache"] == "hit"


def test_no_cache_computes_without_reading_or_writing_the_cache(tmp_path):
    cache = tmp_path / "cache"
    hopf = ["hopf", "--config", "nes", "--Fz", "150000"]
    assert json.loads(shimmy(cache, *hopf, "--json")[0].stdout)["cache"] == "miss"
    stored = entries(cache)
    out, loaded = shimmy(cache, *hopf, "--json", "--no-cache", importtime=True)
    assert json.loads(out.stdout)["cache"] == "off" and computed(loaded) and entries(cache) == stored
    assert without_cache_line(shimmy(cache, *hopf, "--no-cache")[0].stdout)[1] == "computed without the cache " \
                                                                                  "(--no-cache)"
    # A cache directory that cannot be used (others may write to it): refused by name, unless --no-cache.
    shared = tmp_path / "shared"
    shared.mkdir(mode=0o777)
    shared.chmod(0o777)
    out, _ = shimmy(shared, *hopf)
    assert out.returncode == 2 and out.stdout == ""
    assert f"cache directory {shared} is writable by group or others" in out.stderr and "--no-cache" in out.stderr
    out, _ = shimmy(shared, *hopf, "--no-cache", "--json")
    assert out.returncode == 0 and json.loads(out.stdout)["cache"] == "off"
    assert list(shared.iterdir()) == []


@pytest.mark.parametrize("args, why", [
    (["bifurcation", "--config", "nes", "--Fz", "150000", "--v-max", "80", "--ds-max", "0.4", "--progress", "none"],
     "--ds-max: not in the API's request"),
    (["simulate", "--config", "nes", "--V", "30", "--Fz", "150000", "--t-end", "2", "--csv", "{tmp}/run.csv"],
     "--csv needs the time series, which the cache does not hold"),
])
def test_questions_the_api_cannot_ask_are_computed_without_the_cache(tmp_path, args, why):
    cache = tmp_path / "cache"
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    out, _ = shimmy(cache, *args)
    assert out.returncode == 0, out.stderr
    assert without_cache_line(out.stdout)[1] == f"computed without the cache ({why})"
    assert json.loads(shimmy(cache, *args, "--json")[0].stdout)["cache"] == "off"
    assert not (cache / "results").exists() or entries(cache) == 0


@pytest.mark.parametrize("args, needle", [
    (["map", "--config", "nes", "--fz-min", "5e5", "--fz-max", "1e5"],
     "fz_max=100000.0 must exceed fz_min"),
    (["ground-run", "--config", "nes", "--profile", "takeoff", "--series-dt", "2"],
     "series_dt=2 is out of range; allowed: a number in [0.001, 1] s"),
    (["study", "--param", "e_p", "--values", "0.001", "--param2", "r2"],
     "values2 is required when the other of parameter2/values2 is given"),
])
def test_bad_input_is_refused_before_the_cache_is_opened(tmp_path, args, needle):
    out, _ = shimmy(tmp_path / "cache", *args)
    assert out.returncode == 2 and needle in out.stderr and out.stdout == ""
    assert not (tmp_path / "cache").exists()
