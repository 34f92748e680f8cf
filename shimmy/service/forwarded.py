"""The client's address and scheme behind the proxy, believed from that proxy only.

Behind nginx (``python -m shimmy serve``, the image) every request reaches gunicorn from the proxy,
through gunicorn's Unix socket: the connection's address says nothing of the client. nginx puts the
client's address in ``X-Forwarded-For`` and the scheme in ``X-Forwarded-Proto``, replacing whatever the
client sent in them (shimmy.service.nginx). :func:`from_trusted_proxy` wraps the app so that a request
whose connection comes from a peer in ``SHIMMY_TRUSTED_PROXY`` (``unix`` for the socket, or IP
addresses) goes through werkzeug's ``ProxyFix`` with one proxy (the last value of each header, the one
our proxy wrote); any other request keeps the connection's address and scheme, whatever headers it
carries. With the setting empty (the default: gunicorn alone) the headers are never read, so a client
cannot choose the address that its sign-in attempts are counted under.
"""

from __future__ import annotations

import ipaddress
from typing import Callable, Iterable

from werkzeug.middleware.proxy_fix import ProxyFix

from . import settings


def peer_kind(remote_addr: str | None) -> str:
    """``unix`` for a connection without an IP address (gunicorn's Unix socket), else the IP address."""
    try:
        return str(ipaddress.ip_address((remote_addr or "").strip()))
    except ValueError:
        return "unix"


class TrustedProxyFix:
    """WSGI middleware: ``ProxyFix(x_for=1, x_proto=1)`` for requests from ``trusted`` peers only."""

    def __init__(self, app: Callable, trusted: Iterable[str]):
        self.app = app
        self.trusted = frozenset(trusted)
        self.fixed = ProxyFix(app, x_for=1, x_proto=1, x_host=0, x_port=0, x_prefix=0)

    def __call__(self, environ: dict, start_response: Callable) -> Iterable[bytes]:
        if peer_kind(environ.get("REMOTE_ADDR")) in self.trusted:
            return self.fixed(environ, start_response)
        return self.app(environ, start_response)


def from_trusted_proxy(app: Callable) -> Callable:
    """``app`` wrapped to believe the forwarding headers of SHIMMY_TRUSTED_PROXY's peers; ``app`` itself
    when the setting is empty (ProxySettingError for an entry that is not an address)."""
    trusted = settings.trusted_proxies()
    return TrustedProxyFix(app, trusted) if trusted else app
