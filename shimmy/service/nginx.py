"""The buffering reverse proxy in front of gunicorn: nginx's configuration, rendered from the settings.

gunicorn's workers (gthread) give a thread to each connection they read, so a client that sends its
request slowly, or never finishes it, holds a thread. nginx reads every request whole before it passes
it on (``proxy_request_buffering on``) and takes every answer whole from gunicorn before it sends it
(``proxy_buffering on``), so gunicorn only ever sees complete requests arriving at once, over a Unix
socket that only the proxy reaches. Its documented options bound what a client may hold:

* ``client_header_timeout``: a request's headers complete within ``SHIMMY_HEADER_READ_SECONDS``;
* ``client_body_timeout``: a body pausing at most ``SHIMMY_BODY_READ_SECONDS`` between two reads;
* ``client_max_body_size``: at most ``MAX_BODY_BYTES`` (413, in the API's JSON shape);
* ``send_timeout``: a client reading the answer pauses at most ``SHIMMY_SEND_SECONDS``;
* ``keepalive_timeout`` / ``keepalive_requests``: an idle connection closed after
  ``SHIMMY_KEEPALIVE_SECONDS``, or after ``KEEPALIVE_REQUESTS`` requests;
* ``reset_timedout_connection``: a connection that timed out is reset, its memory freed at once.

A connection that misses a deadline is closed without an answer (nginx's way; it logs 408). The
proxy also writes the client's address into ``X-Forwarded-For`` and the scheme into
``X-Forwarded-Proto``, replacing what the client sent, for :mod:`shimmy.service.forwarded`.

``python -m shimmy nginx-conf`` prints the configuration; ``python -m shimmy serve``
(:mod:`shimmy.service.serve`) writes it and runs nginx with gunicorn behind it.
"""

from __future__ import annotations

import ipaddress
import os
import pwd
import re
import shutil
from pathlib import Path

from . import settings

#: Where Debian's nginx package puts the binary (not on a non-root user's PATH there).
NGINX_CANDIDATES = ("/usr/sbin/nginx", "/usr/local/sbin/nginx", "/usr/local/nginx/sbin/nginx")
#: Characters allowed in a path written into the configuration (no quoting, no directive injection).
_SAFE_PATH = re.compile(r"^/[A-Za-z0-9_./@+-]*$")

TEMPLATE = """\
# nginx in front of gunicorn for the shimmy service: rendered by `python -m shimmy nginx-conf` (or written by
# `python -m shimmy serve`) from the service's settings; shimmy/service/nginx.py says why each line is here.
daemon off;
worker_processes %(worker_processes)d;
pid %(run_dir)s/nginx.pid;
error_log stderr warn;
%(user)s
events {
    worker_connections %(worker_connections)d;
}

http {
    server_tokens off;
    access_log %(access_log)s;
    default_type application/octet-stream;

    # Temporary files under the run directory, so that nginx runs as any user.
    client_body_temp_path %(run_dir)s/client_body;
    proxy_temp_path %(run_dir)s/proxy;
    fastcgi_temp_path %(run_dir)s/fastcgi;
    uwsgi_temp_path %(run_dir)s/uwsgi;
    scgi_temp_path %(run_dir)s/scgi;

    # Slow clients wait here, never in gunicorn: deadlines on every read and write of a client.
    # SHIMMY_HEADER_READ_SECONDS: the whole headers; SHIMMY_BODY_READ_SECONDS: a pause between two reads of
    # the body; SHIMMY_SEND_SECONDS: a pause between two writes of the answer; SHIMMY_KEEPALIVE_SECONDS: idle.
    client_header_timeout %(header_seconds)s;
    client_body_timeout %(body_seconds)s;
    send_timeout %(send_seconds)s;
    keepalive_timeout %(keepalive_seconds)s;
    keepalive_requests %(keepalive_requests)d;
    reset_timedout_connection on;
    # MAX_BODY_BYTES: 413 beyond; a whole body is kept in memory, never written to disk.
    client_max_body_size %(max_body)d;
    client_body_buffer_size %(max_body)d;
    client_header_buffer_size 1k;
    large_client_header_buffers 4 8k;

    upstream shimmy_app {
        server %(upstream)s;
    }

    server {
        listen %(listen)s;

        location / {
            proxy_pass http://shimmy_app;
            proxy_http_version 1.1;
            # The app gets a request once it is complete, and hands its answer over at once.
            proxy_request_buffering on;
            proxy_buffering on;
            # Replaced, never appended to: what a client sends in them does not reach the app.
            proxy_set_header Host $http_host;
            proxy_set_header X-Forwarded-For $remote_addr;
            proxy_set_header X-Real-IP $remote_addr;
            proxy_set_header X-Forwarded-Proto $scheme;
            proxy_connect_timeout 5s;
            proxy_send_timeout 30s;
            # gunicorn's worker timeout (settings.REQUEST_SECONDS)
            proxy_read_timeout %(request_seconds)ds;
        }

        error_page 413 @body_too_large;
        location @body_too_large {
            default_type application/json;
            return 413 '{"error": "request body above the limit of %(max_body)d bytes", "field": "body", \
"allowed": "at most %(max_body)d bytes"}';
        }
        # A request line or a header line above large_client_header_buffers (8 kB): the API's refusal, not
        # nginx's page. By URI: an error_page to a named location answered 500 here (the request not parsed).
        error_page 414 /__shimmy_request_line_too_long;
        location = /__shimmy_request_line_too_long {
            internal;
            default_type application/json;
            return 414 '{"error": "request line (method, path and query) above the limit of 8192 bytes", \
"field": "request line", "allowed": "at most 8192 bytes"}';
        }
        error_page 494 =431 /__shimmy_headers_too_large;
        location = /__shimmy_headers_too_large {
            internal;
            default_type application/json;
            return 431 '{"error": "request headers above the limit of 8192 bytes a line, 32768 in all", \
"field": "headers", "allowed": "at most 8192 bytes a line, 32768 in all"}';
        }
        error_page 502 503 =503 @app_unavailable;
        location @app_unavailable {
            default_type application/json;
            add_header Retry-After 5 always;
            return 503 '{"error": "the application server is not answering (starting or restarting); try again \
in a few seconds"}';
        }
        error_page 504 @app_timeout;
        location @app_timeout {
            default_type application/json;
            return 504 '{"error": "the application server did not answer within %(request_seconds)d s"}';
        }
    }
}
"""


class ProxyConfigError(ValueError):
    """A value that cannot go into the proxy's configuration; the message names the option."""


def parse_listen(value: str) -> str:
    """nginx's ``listen`` of ``HOST:PORT``, ``[IPv6]:PORT`` or ``PORT`` (ProxyConfigError otherwise)."""
    text = value.strip()
    allowed = "HOST:PORT (e.g. 0.0.0.0:8050, 127.0.0.1:8050, [::]:8050) or PORT, port 1 to 65535"
    match = re.fullmatch(r"(?:(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9.-]+):)?([0-9]{1,5})", text)
    if not match or not 1 <= int(match.group(2)) <= 65535:
        raise ProxyConfigError(f"--listen={value!r} is not an address to listen on; allowed: {allowed}")
    host = match.group(1)
    if host and host.startswith("["):
        try:
            ipaddress.IPv6Address(host[1:-1])
        except ValueError:
            raise ProxyConfigError(f"--listen={value!r}: {host} is not an IPv6 address; allowed: {allowed}") from None
    return text


def parse_upstream(value: str) -> str:
    """nginx's ``server`` of gunicorn's address: ``unix:/PATH`` or ``HOST:PORT`` (ProxyConfigError otherwise)."""
    if value.startswith("unix:"):
        if not _SAFE_PATH.match(value[5:]):
            raise ProxyConfigError(f"--upstream={value!r}: the socket's path must be absolute and made of letters, "
                                   "digits and _ . / @ + - only")
        return value
    try:
        return parse_listen(value)
    except ProxyConfigError:
        raise ProxyConfigError(f"--upstream={value!r} is not gunicorn's address; allowed: unix:/PATH or "
                               "HOST:PORT") from None


def _path(option: str, value: Path | str) -> str:
    text = str(value)
    if not _SAFE_PATH.match(text):
        raise ProxyConfigError(f"{option}={text!r}: the path must be absolute and made of letters, digits and "
                               "_ . / @ + - only")
    return text.rstrip("/") or "/"


def _seconds(value: float) -> str:
    """nginx's time of ``value`` seconds: whole seconds, or milliseconds for a fraction."""
    return f"{int(value)}s" if float(value).is_integer() else f"{int(round(value * 1000))}ms"


def render(listen: str, upstream: str, run_dir: Path | str, access_log: str = "/dev/stdout",
           worker_processes: int = 1, worker_connections: int = 1024) -> str:
    """The configuration of nginx listening on ``listen`` in front of gunicorn at ``upstream``, its pid and
    temporary files under ``run_dir``, with the limits of ``shimmy.service.settings``. When started by
    root, its workers run as root too (nginx would take ``nobody``, who may not reach the socket)."""
    user = "" if os.geteuid() != 0 else f"user {pwd.getpwuid(os.geteuid()).pw_name};"
    for name, value in (("SHIMMY_HEADER_READ_SECONDS", settings.HEADER_READ_SECONDS),
                        ("SHIMMY_BODY_READ_SECONDS", settings.BODY_READ_SECONDS),
                        ("SHIMMY_SEND_SECONDS", settings.SEND_SECONDS),
                        ("SHIMMY_KEEPALIVE_SECONDS", settings.KEEPALIVE_SECONDS)):
        if not 0.001 <= value <= 3600:
            raise ProxyConfigError(f"{name}={value:g} s is out of range; allowed: 0.001 to 3600 s")
    access = "off" if access_log == "off" else _path("--access-log", access_log)
    return TEMPLATE % {
        "worker_processes": worker_processes, "worker_connections": worker_connections,
        "run_dir": _path("--run-dir", run_dir), "user": user, "access_log": access,
        "header_seconds": _seconds(settings.HEADER_READ_SECONDS), "body_seconds": _seconds(settings.BODY_READ_SECONDS),
        "send_seconds": _seconds(settings.SEND_SECONDS), "keepalive_seconds": _seconds(settings.KEEPALIVE_SECONDS),
        "keepalive_requests": settings.KEEPALIVE_REQUESTS, "max_body": settings.MAX_BODY_BYTES,
        "upstream": parse_upstream(upstream), "listen": parse_listen(listen),
        "request_seconds": settings.REQUEST_SECONDS,
    }


def binary() -> str | None:
    """The nginx executable: on PATH, or where Debian and the sources install it; None if there is none."""
    found = shutil.which("nginx")
    if found:
        return found
    return next((p for p in NGINX_CANDIDATES if os.access(p, os.X_OK)), None)


def command(nginx: str, run_dir: Path | str, conf: Path | str) -> list[str]:
    """nginx in the foreground on ``conf``, its prefix ``run_dir``, logging to stderr from the start."""
    return [nginx, "-p", str(run_dir), "-c", str(conf), "-e", "stderr"]
