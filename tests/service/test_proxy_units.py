"""Behind the proxy, without a server: whose forwarding headers the app believes, and where the server counts as
listening (which decides the authentication default)."""

from __future__ import annotations

import flask
import pytest

from shimmy.service import forwarded, settings

SPOOF = {"X-Forwarded-For": "203.0.113.9", "X-Forwarded-Proto": "https"}


def make_app(monkeypatch, trusted: str | None):
    """A Flask app wrapped as app.py wraps the workbench's, with SHIMMY_TRUSTED_PROXY=``trusted`` (unset: None)."""
    if trusted is None:
        monkeypatch.delenv("SHIMMY_TRUSTED_PROXY", raising=False)
    else:
        monkeypatch.setenv("SHIMMY_TRUSTED_PROXY", trusted)
    server = flask.Flask("probe")
    server.last = {}

    @server.route("/")
    def probe():
        server.last = {"remote_addr": flask.request.remote_addr, "scheme": flask.request.scheme}
        return "ok"

    server.wsgi_app = forwarded.from_trusted_proxy(server.wsgi_app)
    return server


def seen(server, remote_addr: str, headers: dict[str, str]) -> tuple[str, str]:
    """(remote_addr, scheme) of a request from ``remote_addr`` with ``headers``, as a Flask view sees them."""
    assert server.test_client().get("/", headers=headers, environ_base={"REMOTE_ADDR": remote_addr}).status_code == 200
    return server.last["remote_addr"], server.last["scheme"]


def test_without_a_proxy_no_header_chooses_the_client_address(monkeypatch):
    app = make_app(monkeypatch, None)
    assert seen(app, "198.51.100.4", SPOOF) == ("198.51.100.4", "http")
    assert seen(app, "127.0.0.1", {**SPOOF, "X-Real-IP": "10.0.0.1", "Forwarded": "for=10.0.0.2"}) == \
        ("127.0.0.1", "http")


def test_behind_the_proxy_its_headers_are_believed_from_it_only(monkeypatch):
    app = make_app(monkeypatch, "unix")
    assert seen(app, "", SPOOF) == ("203.0.113.9", "https")  # from gunicorn's Unix socket: the proxy
    assert seen(app, "", {"X-Forwarded-For": "10.1.1.1, 203.0.113.9"}) == ("203.0.113.9", "http")  # its own, last
    assert seen(app, "", {}) == ("", "http")
    assert seen(app, "198.51.100.4", SPOOF) == ("198.51.100.4", "http")  # another peer's headers are not
    app = make_app(monkeypatch, "127.0.0.1, ::1")
    assert seen(app, "127.0.0.1", SPOOF) == ("203.0.113.9", "https")
    assert seen(app, "127.0.0.2", SPOOF) == ("127.0.0.2", "http")
    assert seen(app, "", SPOOF) == ("", "http")


def test_a_trusted_proxy_setting_that_is_not_an_address_is_refused(monkeypatch):
    monkeypatch.setenv("SHIMMY_TRUSTED_PROXY", "unix,proxy.example")
    with pytest.raises(settings.ProxySettingError, match="SHIMMY_TRUSTED_PROXY=.*'proxy.example'"):
        settings.trusted_proxies()


@pytest.mark.parametrize("listen, proxy, addresses, mode", [
    ("unix:/run/shimmy/gunicorn.sock", "127.0.0.1:8050", ["127.0.0.1:8050"], "none"),
    ("unix:/run/shimmy/gunicorn.sock", "0.0.0.0:8050", ["0.0.0.0:8050"], "token"),
    ("unix:/run/shimmy/gunicorn.sock", None, ["unix:/run/shimmy/gunicorn.sock"], "token"),
    ("unix:/x.sock,0.0.0.0:9000", "127.0.0.1:8050", ["0.0.0.0:9000", "127.0.0.1:8050"], "token"),
])
def test_behind_the_proxy_the_server_listens_where_the_proxy_does(monkeypatch, listen, proxy, addresses, mode):
    for name in ("SHIMMY_AUTH", "SHIMMY_ALLOW_ANONYMOUS", "SHIMMY_PROXY_LISTEN"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("SHIMMY_LISTEN", listen)
    if proxy:
        monkeypatch.setenv("SHIMMY_PROXY_LISTEN", proxy)
    assert settings.listen_addresses() == addresses
    assert settings.auth_mode() == mode
