"""The service warms a map from the nearest cached design, and only within reach; --no-cache
(cache.bypassed) computes cold. The warm map's equality to the cold one is tested in
tests/analyses/maps/test_warm_map.py; here: which map is warmed from which."""

import pytest

from shimmy.service import analyses, cache, neighbours

BODY = {"config": "nes", "fz_min": 3.0e5, "fz_max": 9.0e5, "resolution": 4, "n_v": 40}


@pytest.fixture
def store(tmp_path, monkeypatch):
    monkeypatch.setenv("SHIMMY_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path


def test_a_map_one_step_away_is_warmed_from_the_cached_one(store):
    first, hit = analyses.run("map", BODY)
    assert not hit and "warmed_from" not in first["methods"]
    step, hit = analyses.run("map", dict(BODY, params={"e_p": 0.0011}))
    assert not hit
    assert step["methods"]["warmed_from"]["changed"] == {"e_p": [0.001, 0.0011]}
    assert step["methods"]["warmed_from"]["params"] == first["params"]
    # both designs are listed now: a third step warms from the nearest of them (e_p 0.0011)
    third, _ = analyses.run("map", dict(BODY, params={"e_p": 0.00115}))
    assert third["methods"]["warmed_from"]["params"]["e_p"] == 0.0011
    # far away: cold
    far, _ = analyses.run("map", dict(BODY, params={"e_p": 0.004}))
    assert "warmed_from" not in far["methods"] and "warm_refused" not in far["methods"]
    # bypassing the cache (the command line's --no-cache): cold, and nothing added to the index
    request = analyses.schemas.validate("map", dict(BODY, params={"e_p": 0.00105}))
    with cache.bypassed():
        cold = analyses.RUNNERS["map"](request)
        assert neighbours.nearest("map", request) is None
    assert "warmed_from" not in cold["methods"]
    assert neighbours.nearest("map", request)["params"]["e_p"] in (0.001, 0.0011)


def test_the_index_lists_each_design_once_and_at_most_keep(store, monkeypatch):
    monkeypatch.setattr(neighbours, "KEEP", 3)
    request = analyses.schemas.validate("map", BODY)
    for e_p in (0.001, 0.0011, 0.0012, 0.0011, 0.0013):
        r = dict(request, params=dict(request["params"], e_p=e_p))
        neighbours.remember("map", r, {"marker": e_p})
    listed = cache.results().get(neighbours._question("map", request))
    assert [e["params"]["e_p"] for e in listed] == [0.0013, 0.0011, 0.0012]
    here = dict(request, params=dict(request["params"], e_p=0.00121))
    assert neighbours.nearest("map", here) == {"marker": 0.0012}
    assert neighbours.nearest("map", dict(request, params=dict(request["params"], e_p=0.003))) is None
