"""Service pieces without a server: canonical requests, cache keys, the URL design state."""

import time

import pytest

from shimmy.errors import InvalidParameterError
from shimmy.model.parameters import Parameters
from shimmy.service import cache, schemas


def test_canonical_request_fills_defaults_and_the_whole_design():
    req = schemas.validate("simulate", {"config": "nes", "V": 30, "Fz": 150000})
    assert req["t_end"] == 60.0 and req["include_series"] is False
    assert req["params"] == Parameters().to_dict()
    tungsten = schemas.validate("simulate", {"config": "nes", "V": 30, "Fz": 150000, "material": "tungsten"})
    assert tungsten["params"]["rho_p"] == 16500 and "material" not in tungsten


def test_equal_questions_have_equal_cache_keys():
    a = schemas.validate("hopf", {"config": "nes", "Fz": 150000, "params": {"r2": 0.08}})
    b = schemas.validate("hopf", {"config": "nes", "Fz": 150000.0, "v_min": 1, "params": {}})
    c = schemas.validate("hopf", {"config": "nes", "Fz": 150000, "params": {"r2": 0.081}})
    assert cache.key("hopf", a) == cache.key("hopf", b) != cache.key("hopf", c)
    assert cache.key("hopf", a) != cache.key("stability", a)


def test_a_parameter_outside_the_configurations_model_is_not_part_of_its_key():
    """The NES's e_p does not enter the original gear (nor the damper's a_p the NES gear): their maps,
    diagrams and Hopf points are one entry however those sliders stand; analyses that report or
    sample parameter values (sensitivity, robustness, studies) key every parameter."""
    def key(analysis, config, **params):
        return cache.key(analysis, schemas.validate(analysis, {"config": config, "Fz": 150000, "params": params}))

    assert key("hopf", "original", e_p=0.002) == key("hopf", "original", e_p=0.003) == key("hopf", "original")
    assert key("hopf", "nes", e_p=0.002) != key("hopf", "nes", e_p=0.003)
    assert key("hopf", "nes", a_p=0.8) == key("hopf", "nes", a_p=0.9) != key("hopf", "nes_pd", a_p=0.8)
    assert key("hopf", "nes_pd", a_p=0.8) != key("hopf", "nes_pd", a_p=0.9)
    assert key("hopf", "original", k_psi=4e5) != key("hopf", "original")
    for analysis, extra in (("map", {}), ("bifurcation", {"Fz": 150000}), ("hopf_curves", {}), ("margin_map", {})):
        a = schemas.validate(analysis, {"config": "pd", "params": {"r2": 0.075}, **extra})
        b = schemas.validate(analysis, {"config": "pd", "params": {"r2": 0.085}, **extra})
        assert cache.key(analysis, a) == cache.key(analysis, b), analysis
    a = schemas.validate("sensitivity", {"config": "original", "Fz": 150000, "params": {"e_p": 0.002}})
    b = schemas.validate("sensitivity", {"config": "original", "Fz": 150000, "params": {"e_p": 0.003}})
    assert cache.key("sensitivity", a) != cache.key("sensitivity", b)


def test_a_shared_entry_answers_with_the_askers_parameters(tmp_path, monkeypatch):
    """Computed once for e_p = 2 mm, the original gear's Hopf points answer a request at e_p = 3 mm from
    the cache: the same numbers, its params the request's."""
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    from shimmy.service import analyses

    first, cached = analyses.run("hopf", {"config": "original", "Fz": 150000, "params": {"e_p": 0.002}})
    again, cached_again = analyses.run("hopf", {"config": "original", "Fz": 150000, "params": {"e_p": 0.003}})
    assert not cached and cached_again
    assert first["params"]["e_p"] == 0.002 and again["params"]["e_p"] == 0.003
    assert {k: v for k, v in again.items() if k != "params"} == {k: v for k, v in first.items() if k != "params"}


def test_a_design_step_recomputes_the_growth_rates_of_the_configurations_it_enters(tmp_path, monkeypatch):
    """The Overview's growth rates of the four configurations are cached each by its own model's
    parameters: an NES step (r2) recomputes nes and nes_pd only, and the answer equals the one
    computed whole (:func:`~shimmy.analyses.core.stability.growth_rates`); ``--no-cache`` reads and
    writes none of them."""
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    from shimmy.analyses.core import stability
    from shimmy.service import analyses

    computed = []
    real = stability.growth_rate
    monkeypatch.setattr(stability, "growth_rate", lambda config, *a, **kw: computed.append(config.value) or real(
        config, *a, **kw))
    body = {"Fz": 150000, "v_max": 200, "n_points": 40}
    analyses.run("stability", {**body, "params": {"r2": 0.08}})
    assert sorted(computed) == ["nes", "nes_pd", "original", "pd"]
    computed.clear()
    stepped, cached = analyses.run("stability", {**body, "params": {"r2": 0.082}})
    assert not cached and sorted(computed) == ["nes", "nes_pd"]
    whole = stability.growth_rates(150000, params=Parameters().with_overrides({"r2": 0.082}), v_range=(1.0, 200.0),
                                   n_points=40)
    assert stepped["configs"] == whole["configs"] and stepped["V"] == whole["V"]
    computed.clear()
    with cache.bypassed():
        analyses.RUNNERS["stability"](schemas.validate("stability", {**body, "params": {"r2": 0.082}}))
    assert sorted(computed) == ["nes", "nes_pd", "original", "pd"]


@pytest.mark.parametrize("body,field", [
    ({"config": "nes", "V": 30, "Fz": 150000, "params": {"r2": 0.2}}, "params.r2"),
    ({"config": "nes", "V": 30, "Fz": 150000, "params": {"n": 2.5}}, "params.n"),
    ({"config": "nes", "V": 30, "Fz": 150000, "params": {"zz": 1}}, "params.zz"),
    ({"config": "nes", "V": 30, "Fz": 150000, "t_end": 601}, "t_end"),
    ({"config": "nes", "V": 30, "Fz": 150000, "exact_nes": "yes"}, "exact_nes"),
    ({"config": "nes", "V": 30, "Fz": 150000, "material": 3}, "material"),
])
def test_refusals_name_the_field(body, field):
    with pytest.raises(InvalidParameterError) as info:
        schemas.validate("simulate", body)
    assert info.value.field == field


@pytest.mark.parametrize("analysis,body,message", [
    # a value of the wrong type says so, with the value as given (not "out of range", not its type's name)
    ("ground_run", {"config": "nes", "profile": "x"}, "profile='x' is not a list of rows"),
    ("ground_run", {"config": "nes", "profile": [[0, 30, 1e5]]}, "profile has 1 rows; allowed: a list of 2 to"),
    ("simulate", {"config": "nes", "V": 30, "Fz": 150000, "x0": "x"}, "x0='x' is not a list"),
    ("simulate", {"config": "nes", "V": 30, "Fz": 150000, "x0": [[1]]}, "x0[0]=[1] is not a number"),
    ("sensitivity", {"config": "nes", "names": "r2"}, "names='r2' is not a list"),
    ("sensitivity", {"config": "nes", "names": []}, "names=[] is empty"),
    ("ground_run", {"config": "nes", "preset_options": "x"}, "allowed: an object {setting name: number}: settings"),
    ("ground_run", {"config": "nes", "preset": "landing", "preset_options": {"V_touchdown": "70"}},
     "preset_options.V_touchdown='70' is not a number; allowed: a number in [20, 150] m/s"),
    ("simulate", {"config": "nes", "V": 30, "Fz": 150000, "series_dt": 0.0024},
     "series_dt=0.0024 is not a multiple of 0.001 s"),
])
def test_refusals_say_what_is_wrong_with_the_value(analysis, body, message):
    with pytest.raises(InvalidParameterError) as info:
        schemas.validate(analysis, body)
    assert message in str(info.value)


def test_every_analysis_is_declared_once_with_its_schema_and_runner():
    """The registries derive from one declaration per analysis (schema, runner, sync or job)."""
    from shimmy.service import analyses

    assert list(analyses.ANALYSES) == list(analyses.RUNNERS) and set(analyses.ANALYSES) == set(schemas.SCHEMAS)
    for name, a in analyses.ANALYSES.items():
        assert a.schema is schemas.SCHEMAS[name] and (a.sync or a.job), name
    assert analyses.SYNC_ANALYSES == ("simulate", "hopf", "stability", "devices", "sensitivity")
    assert analyses.JOB_ANALYSES == ("simulate", "bifurcation", "hopf_curves", "map", "study", "ground_run",
                                     "sensitivity", "optimise", "robustness", "margins", "basins", "margin_map")


def test_openapi_fields_match_the_schemas():
    from shimmy.service.api import openapi_document

    doc = openapi_document()
    from shimmy.service.api import JOB_ANALYSES, SYNC_ANALYSES

    for name in SYNC_ANALYSES:
        props = doc["components"]["schemas"][f"{name}_request"]["properties"]
        assert set(props) == {f.name for f in schemas.SCHEMAS[name].fields}
    for name in JOB_ANALYSES:
        assert doc["components"]["schemas"][f"job_{name}"]["properties"]["analysis"]["enum"] == [name]
    # The document says exactly which design parameters the server takes, with their ranges.
    from shimmy.model.parameters import PARAMETER_SPECS

    params = doc["components"]["schemas"]["hopf_request"]["properties"]["params"]
    assert params["additionalProperties"] is False and set(params["properties"]) == set(PARAMETER_SPECS)
    assert (params["properties"]["r2"]["minimum"], params["properties"]["r2"]["maximum"]) == (0.07, 0.09)
    assert "Retry-After" in doc["paths"]["/jobs"]["post"]["responses"]["429"]["headers"]


# Requests the document's JSON Schema admits but a rule across fields refuses: each refusal names a field
# that the request schema's description states the rule for (an outside client that generates requests
# from the document meets no unstated rule).
ACROSS_FIELDS = [
    ("hopf", {"config": "nes", "Fz": 150000, "v_min": 100, "v_max": 50}, "v_max"),
    ("map", {"config": "nes", "fz_min": 500000, "fz_max": 100000}, "fz_max"),
    ("simulate", {"config": "nes", "V": 30, "Fz": 150000, "params": {"r2": 0.07, "r3": 0.0095, "r1": 0.13}},
     "params"),
    ("simulate", {"config": "nes", "V": 30, "Fz": 150000, "t_end": 600, "include_series": True,
                  "series_dt": 0.001}, "series_dt"),
    ("study", {"parameter": "r2", "values": [0.07], "parameter2": "r2", "values2": [0.08]}, "parameter2"),
    ("study", {"parameter": "r2", "values": [0.5]}, "values[0]"),
    ("optimise", {"config": "nes", "starts": 2, "local_runs": 3}, "local_runs"),
    ("optimise", {"config": "nes", "parameters": ["a_p"]}, "parameters[0]"),
    ("robustness", {"config": "nes", "tolerances": ["r2=0.05", "r2=0.01"]}, "tolerances[1].name"),
    ("margins", {"config": "nes", "V": 50, "Fz": 550000, "min_size": 0.05, "max_size": 0.04}, "min_size"),
]


@pytest.mark.parametrize("analysis, body, field", ACROSS_FIELDS)
def test_rules_across_fields_are_stated_in_the_document(analysis, body, field):
    import jsonschema
    from shimmy.errors import GeometryError, InvalidParameterError
    from shimmy.service.api import openapi_document

    doc = openapi_document()
    named_schemas = doc["components"]["schemas"]
    request_schema = named_schemas.get(f"{analysis}_request") or named_schemas[f"job_{analysis}"]
    as_sent = body if f"{analysis}_request" in named_schemas else {"analysis": analysis, **body}
    jsonschema.validate(as_sent, request_schema)  # valid by the document
    with pytest.raises((InvalidParameterError, GeometryError)) as refused:
        from shimmy.service import analyses

        analyses.RUNNERS[analysis](schemas.validate(analysis, body), None)
    named = getattr(refused.value, "field", None) or "params"
    assert named.startswith(field.split("[")[0]) or named == field, (named, field)
    assert field.split("[")[0].split(".")[0] in request_schema["description"]


def test_url_design_state_round_trip_and_bad_keys():
    from ui import state

    material, values, problems = state.design_from_query({"r2": "0.085", "material": "tungsten", "V": "30"})
    assert material == "tungsten" and values["r2"] == 0.085 and values["rho_p"] == 16500 and not problems
    query = state.design_query(material, values)
    assert query == {"material": "tungsten", "r2": "0.085"}
    assert state.design_request(material, values) == {"material": "tungsten", "params": {"r2": 0.085}}
    material, values, problems = state.design_from_query({"r2": "9", "e_p": "x", "material": "gold"})
    assert material == "steel" and values["r2"] == 0.08 and len(problems) == 3


def test_cache_directory_is_private_and_refused_when_shared(tmp_path, monkeypatch):
    import os

    from shimmy.service import settings

    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path / "new"))
    assert settings.cache_dir().stat().st_mode & 0o777 == 0o700
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(shared))
    with pytest.raises(settings.CacheDirectoryError, match="writable by group or others"):
        settings.cache_dir()
    if os.getuid() == 0:  # root can give a directory away: another user's folder is refused
        theirs = tmp_path / "theirs"
        theirs.mkdir(mode=0o700)
        os.chown(theirs, 65534, 65534)
        monkeypatch.setenv("SHIMMY_CACHE_DIR", str(theirs))
        with pytest.raises(settings.CacheDirectoryError, match="belongs to uid 65534"):
            settings.cache_dir()


def test_unusable_cache_is_reported_degraded_while_analyses_answer_uncached(tmp_path, monkeypatch):
    import sqlite3

    from shimmy.service import cache

    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))

    def broken(*args, **kwargs):
        raise sqlite3.OperationalError("disk I/O error")

    monkeypatch.setattr(cache, "open_store", broken)
    import app

    client = app.server.test_client()
    health = client.get("/api/v1/health")
    assert health.status_code == 503 and health.json["status"] == "degraded" and "disk I/O" in health.json["cache"]
    answer = client.post("/api/v1/hopf", json={"config": "nes", "Fz": 150000})
    assert answer.status_code == 200 and answer.headers["X-Shimmy-Cache"] == "miss"


def test_non_json_posts_are_refused_and_responses_carry_security_headers(tmp_path, monkeypatch):
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path))
    import app

    client = app.server.test_client()
    body = '{"config": "nes", "analysis": "simulate", "V": 30, "Fz": 150000}'
    for mimetype in ("text/plain", "application/x-www-form-urlencoded", "multipart/form-data"):
        answer = client.post("/api/v1/jobs", data=body, content_type=mimetype)
        assert answer.status_code == 415 and answer.json["field"] == "Content-Type", mimetype
    answer = client.post("/_dash-update-component", data="{}", content_type="text/plain")
    assert answer.status_code == 415
    for path in ("/", "/api/v1/health", "/api/v1/nothing", "/_dash-layout"):
        headers = client.get(path).headers
        assert headers["X-Content-Type-Options"] == "nosniff", path
        assert "frame-ancestors 'none'" in headers["Content-Security-Policy"], path
        assert headers["X-Frame-Options"] == "DENY" and headers["Referrer-Policy"] == "no-referrer", path
    page = client.get("/").get_data(as_text=True)
    assert "Python/" not in page and "Werkzeug/" not in page


def test_design_schemas_name_what_the_analyses_take():
    """The optimiser's and robustness's names in the request schemas are the analyses' own (the schemas do
    not import the numerics: the web server stays light)."""
    from shimmy.analyses.decisions import optimise, robustness

    assert list(schemas.FIGURE_LIMITS) == list(optimise.FIGURES)
    for name, (unit, at_load, _, _) in schemas.FIGURE_LIMITS.items():
        assert (unit, at_load) == (optimise.FIGURES[name].unit, optimise.FIGURES[name].at_load), name
    assert schemas.DIFFERENTIABLE == optimise.DIFFERENTIABLE
    assert list(schemas.DEFAULT_SEARCH) == optimise.device_parameters("nes_pd")
    assert schemas.DISTRIBUTIONS == robustness.DISTRIBUTIONS
    request = schemas.validate("optimise", {"config": "nes", "constraints": ["interval@200000<=40",
                                                                             "min_shimmy_Fz>=8e4"]})
    assert request["constraints"] == [{"figure": "interval", "op": "<=", "value": 40.0, "Fz": 200000.0},
                                      {"figure": "min_shimmy_Fz", "op": ">=", "value": 80000.0, "Fz": None}]
    assert request["parameters"] == ["r2", "e_p", "k_s", "r3"]
    same = schemas.validate("optimise", {"config": "nes", "constraints": [
        {"figure": "interval", "op": "<=", "value": 40, "Fz": 200000}, {"figure": "min_shimmy_Fz", "op": ">=",
                                                                         "value": 80000}]})
    assert same == request
    a = schemas.validate("robustness", {"config": "nes", "tolerances": ["k_s=0.05:uniform"]})
    b = schemas.validate("robustness", {"config": "nes", "tolerances": [{"name": "k_s", "relative": 0.05,
                                                                         "distribution": "uniform"}]})
    assert a == b and a["tolerances"] == [{"name": "k_s", "relative": 0.05, "distribution": "uniform"}]
    # spaces ignored in reading: the same request; a part refused is quoted as typed, its spaces kept
    assert schemas.validate("robustness", {"config": "nes", "tolerances": [" k _s = 0.05 : uniform "]}) == a
    assert schemas.validate("optimise", {"config": "nes", "constraints": [" interval @ 200 000 <= 40 ",
                                                                          "min_shimmy_Fz > = 8e4"]}) == request
    for analysis, key, typed, said in (("optimise", "constraints", "max_psi <= 0.02 extra",
                                        "constraints[0].value='0.02 extra'"),
                                       ("optimise", "constraints", "max_psi @ 150 kN <= 0.02",
                                        "constraints[0].Fz='150 kN'"),
                                       ("robustness", "tolerances", "k_s = 0.05 extra",
                                        "tolerances[0].relative='0.05 extra'")):
        with pytest.raises(InvalidParameterError) as info:
            schemas.validate(analysis, {"config": "nes", key: [typed]})
        assert said in str(info.value)


CSP_PROBE = r"""
import base64, hashlib, re, sys
import app

server = app.server
# a response served before Dash's first-request hook has registered the pages' document.title script
# (under load another thread's response did come first), then the page itself
with server.test_request_context("/api/v1/health"):
    early = server.process_response(server.make_response(("ok", 200)))
page = server.test_client().get("/")
policy = page.headers["Content-Security-Policy"]
allowed = set(re.findall(r"'sha256-([^']+)'", policy))
html = re.sub(r"<!--\[if IE\]>.*?<!\[endif\]-->", "", page.get_data(as_text=True), flags=re.S)  # never run
scripts = re.findall(r"<script>(.*?)</script>", html, re.S)
scripts += re.findall(r'<script id="_dash-renderer" type="application/javascript">(.*?)</script>', html, re.S)
missing = [s[:80] for s in scripts if base64.b64encode(hashlib.sha256(s.encode()).digest()).decode() not in allowed]
print(len(scripts), "inline scripts;", "missing:", missing)
sys.exit(1 if missing or "document.title" not in "".join(scripts) else 0)
"""


def test_the_pages_policy_names_every_inline_script_even_after_an_early_response(tmp_path):
    """The Content-Security-Policy allows exactly Dash's inline scripts by their hashes. Dash registers the
    last of them (dash pages' document.title callback) in a hook of the first request; a response another
    thread served before that hook had run fixed the policy without it, and every page then failed
    ("Executing inline script violates ..."). In a fresh process: a response first, then the page: every
    inline script of the page is in the page's policy."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(root)}
    run = subprocess.run([sys.executable, "-c", CSP_PROBE], cwd=root, env=env, capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr[-3000:]

def test_the_write_ahead_log_is_truncated_once_a_reader_lets_go(tmp_path):
    """While a reader holds an older snapshot SQLite's checkpoints cannot start the log over, and the
    log grows with the writes (with readers always present, as under a flood of requests on several
    workers, it grew without bound: 32 MB for 48 MB written by two processes while three read; the
    team test's job store reached 19.7 MB on a loaded machine). SQLite never shrinks the file itself:
    the store truncates it at its next use once it is past the limit and no snapshot holds it."""
    import sqlite3

    path = tmp_path / "jobs"
    cache.open_store(path).set("first", 1)
    reader = sqlite3.connect(str(path / "cache.db"), isolation_level=None)
    try:
        reader.execute("BEGIN")
        reader.execute("SELECT count(*) FROM Cache").fetchone()  # a snapshot held
        value = "x" * 8000
        for k in range(1200):  # ~10 MB
            cache.open_store(path).set(("job", k % 100), {"log": value, "k": k})
        held = (path / "cache.db-wal").stat().st_size
        assert held > cache.WAL_LIMIT  # nothing could be done while the snapshot was held
        reader.execute("COMMIT")
    finally:
        reader.close()
    time.sleep(cache.WAL_EVERY_S)
    cache.open_store(path).set(("job", 0), {"log": value, "k": -1})
    assert (path / "cache.db-wal").stat().st_size <= cache.WAL_LIMIT, held
    assert cache.open_store(path).get(("job", 0))["k"] == -1
