"""Slow clients cost a coroutine, never a thread: gunicorn's asyncio worker with the WSGI app
called only on complete requests.

``BufferingWorker`` (``worker_class`` in gunicorn.conf.py, so ``gunicorn app:server`` uses it)
is gunicorn's own ASGI worker: its event loop reads and parses every connection, however
slowly a client sends. The headers of a connection's first request must be complete within
``HEADER_READ_SECONDS`` (later ones are bounded by gunicorn's keep-alive timer). Its app is
:class:`BufferedWSGI`, which collects the whole request body (at most ``MAX_BODY_BYTES``,
within ``BODY_READ_SECONDS``; else 413 or 408 and the connection closed) before it runs the
WSGI app (Flask with the Dash pages and the API) in a bounded thread pool. What a buffering
proxy in front of a sync worker would do, inside the process gunicorn already runs: no second
server to install, configure and supervise in the image, the compose file and the tests.
"""

from __future__ import annotations

import asyncio
import io
import json
import sys
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable

from gunicorn.asgi.protocol import ASGIProtocol
from gunicorn.workers import gasgi
from gunicorn.workers.gasgi import ASGIWorker

from . import settings


class BufferedWSGI:
    """An ASGI app that runs ``wsgi_app`` on complete, bounded requests in ``threads`` threads."""

    def __init__(self, wsgi_app: Callable, threads: int | None = None):
        self.wsgi_app = wsgi_app
        self.pool = ThreadPoolExecutor(max_workers=threads or settings.WEB_THREADS, thread_name_prefix="wsgi")

    async def __call__(self, scope: dict[str, Any], receive, send) -> None:
        if scope["type"] == "lifespan":
            while True:
                message = await receive()
                if message["type"] == "lifespan.startup":
                    await send({"type": "lifespan.startup.complete"})
                elif message["type"] == "lifespan.shutdown":
                    self.pool.shutdown(wait=False, cancel_futures=True)
                    await send({"type": "lifespan.shutdown.complete"})
                    return
        if scope["type"] != "http":
            return
        body = await self._body(receive, send)
        if body is None:
            return
        loop = asyncio.get_running_loop()
        status, headers, content = await loop.run_in_executor(self.pool, self._call, _environ(scope, body))
        await send({"type": "http.response.start", "status": status, "headers": headers})
        await send({"type": "http.response.body", "body": content})

    async def _body(self, receive, send) -> bytes | None:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + settings.BODY_READ_SECONDS
        chunks, size = [], 0
        while True:
            try:
                message = await asyncio.wait_for(receive(), max(deadline - loop.time(), 0.001))
            except asyncio.TimeoutError:
                await _refuse(send, 408, f"the request body did not arrive complete within "
                              f"{settings.BODY_READ_SECONDS:g} s", f"the whole body within "
                              f"{settings.BODY_READ_SECONDS:g} s")
                return None
            if message["type"] == "http.disconnect":
                return None
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > settings.MAX_BODY_BYTES:
                await _refuse(send, 413, f"request body above the limit of {settings.MAX_BODY_BYTES} bytes",
                              f"at most {settings.MAX_BODY_BYTES} bytes")
                return None
            chunks.append(chunk)
            if not message.get("more_body", False):
                return b"".join(chunks)

    def _call(self, environ: dict[str, Any]) -> tuple[int, list[tuple[bytes, bytes]], bytes]:
        started: dict[str, Any] = {}

        def start_response(status, headers, exc_info=None):
            started["status"], started["headers"] = status, headers
            return lambda data: None  # the legacy write() callable; Flask does not use it

        result = self.wsgi_app(environ, start_response)
        try:
            content = b"".join(result)
        finally:
            if hasattr(result, "close"):
                result.close()
        headers = [(k.lower().encode("latin-1"), v.encode("latin-1")) for k, v in started["headers"]]
        return int(started["status"].split(" ", 1)[0]), headers, content


async def _refuse(send, status: int, message: str, allowed: str) -> None:
    body = json.dumps({"error": message, "field": "body", "allowed": allowed}).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"), (b"connection", b"close"),
                            (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})


def _environ(scope: dict[str, Any], body: bytes) -> dict[str, Any]:
    """The PEP 3333 environ of an ASGI http scope and its complete body."""
    server = scope.get("server") or ("127.0.0.1", 80)
    client = scope.get("client") or ("", 0)
    environ = {
        "REQUEST_METHOD": scope["method"], "SCRIPT_NAME": scope.get("root_path", ""),
        "PATH_INFO": scope["path"].encode("utf-8").decode("latin-1"),
        "QUERY_STRING": scope.get("query_string", b"").decode("latin-1"),
        "SERVER_NAME": str(server[0]), "SERVER_PORT": str(server[1] or 80),
        "SERVER_PROTOCOL": f"HTTP/{scope.get('http_version', '1.1')}", "REMOTE_ADDR": str(client[0]),
        "REMOTE_PORT": str(client[1]), "CONTENT_LENGTH": str(len(body)),
        "wsgi.version": (1, 0), "wsgi.url_scheme": scope.get("scheme", "http"), "wsgi.input": io.BytesIO(body),
        "wsgi.errors": sys.stderr, "wsgi.multithread": True, "wsgi.multiprocess": True, "wsgi.run_once": False,
    }
    for raw_name, raw_value in scope.get("headers", []):
        name, value = raw_name.decode("latin-1").upper().replace("-", "_"), raw_value.decode("latin-1")
        if name == "CONTENT_TYPE":
            environ["CONTENT_TYPE"] = value
        elif name != "CONTENT_LENGTH":
            key = f"HTTP_{name}"
            environ[key] = f"{environ[key]},{value}" if key in environ else value
    return environ


class HeaderDeadlineProtocol(ASGIProtocol):
    """gunicorn's connection protocol, closing a connection whose first request's headers are not
    complete within HEADER_READ_SECONDS (gunicorn itself waits for them without a limit)."""

    def connection_made(self, transport):
        super().connection_made(transport)
        self._header_deadline = self.worker.loop.call_later(settings.HEADER_READ_SECONDS, self._headers_late)

    def _headers_late(self):
        ready = getattr(self, "_request_ready", None)
        if self.req_count <= 1 and ready is not None and not ready.is_set():
            self._keepalive_timeout()  # closes the transport and wakes the connection's loop

    def connection_lost(self, exc):
        self._header_deadline.cancel()
        super().connection_lost(exc)


# The worker builds its connections with the module's ASGIProtocol (no hook for another class).
gasgi.ASGIProtocol = HeaderDeadlineProtocol


class BufferingWorker(ASGIWorker):
    """gunicorn's asyncio worker serving a WSGI app through :class:`BufferedWSGI`."""

    def load_wsgi(self):
        super().load_wsgi()
        self.asgi = BufferedWSGI(self.asgi)
