"""The workbench's scripts and answers are sent compressed to a client that accepts it (the pages
load 6.3 MB of component bundles), and as they are to one that does not. Against the real gunicorn
of the suite (tests/conftest.py)."""

from __future__ import annotations

import gzip
import json
import re
import urllib.request


def _get(server, path: str, encoding: str | None):
    headers = {"Accept-Encoding": encoding} if encoding else {}
    with urllib.request.urlopen(urllib.request.Request(server.base + path, headers=headers), timeout=60) as resp:
        return resp.read(), resp.headers.get("Content-Encoding")


def _largest_script(server) -> str:
    html, _ = _get(server, "/stability-map", None)
    scripts = re.findall(r'src="([^"]+\.js[^"]*)"', html.decode())
    sizes = {s: len(_get(server, s, None)[0]) for s in scripts}
    return max(sizes, key=sizes.get)


def test_bundles_are_sent_compressed_to_a_browser_that_accepts_it(server):
    path = _largest_script(server)
    plain, none = _get(server, path, None)
    packed, how = _get(server, path, "gzip")
    assert none is None and how == "gzip"
    assert gzip.decompress(packed) == plain
    assert len(packed) < 0.4 * len(plain), (len(packed), len(plain))


def test_api_answers_are_compressed_only_when_asked(server):
    body = json.dumps({"config": "nes", "Fz": 150e3}).encode()

    def hopf(encoding):
        headers = {"Content-Type": "application/json", **({"Accept-Encoding": encoding} if encoding else {})}
        req = urllib.request.Request(server.base + "/api/v1/hopf", data=body, headers=headers, method="POST")
        with urllib.request.urlopen(req, timeout=60) as resp:
            return resp.read(), resp.headers.get("Content-Encoding")

    plain, none = hopf(None)
    packed, how = hopf("gzip")
    assert none is None and json.loads(plain)["config"] == "nes"
    assert how in (None, "gzip")  # a short answer (under 500 bytes) is sent as it is
    assert json.loads(gzip.decompress(packed) if how == "gzip" else packed) == json.loads(plain)
