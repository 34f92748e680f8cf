"""Real servers for the service tests: gunicorn serving app:server on a loopback port."""

from __future__ import annotations

import contextlib
import json
import os
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    def __init__(self, base: str, cache_dir: Path, proc: subprocess.Popen):
        self.base, self.cache_dir, self.proc = base, cache_dir, proc

    @contextlib.contextmanager
    def cache_env(self):
        """SHIMMY_CACHE_DIR set to this server's cache while the block runs (to read its job store)."""
        before = os.environ.get("SHIMMY_CACHE_DIR")
        os.environ["SHIMMY_CACHE_DIR"] = str(self.cache_dir)
        try:
            yield
        finally:
            if before is None:
                os.environ.pop("SHIMMY_CACHE_DIR", None)
            else:
                os.environ["SHIMMY_CACHE_DIR"] = before

    def request(self, method: str, path: str, body=None, raw: bytes | None = None, timeout: float = 60.0):
        """(status, headers, parsed JSON or text) of one request."""
        data = raw if raw is not None else (None if body is None else json.dumps(body).encode())
        req = urllib.request.Request(self.base + path, data=data, method=method,
                                     headers={"Content-Type": "application/json"} if data is not None else {})
        try:
            with urllib.request.urlopen(req, timeout=timeout) as resp:
                status, headers, text = resp.status, dict(resp.headers), resp.read().decode()
        except urllib.error.HTTPError as exc:
            status, headers, text = exc.code, dict(exc.headers), exc.read().decode()
        try:
            return status, headers, json.loads(text)
        except ValueError:
            return status, headers, text


@pytest.fixture(scope="session")
def server(tmp_path_factory):
    """gunicorn app:server with 2 workers and a fresh shared cache directory."""
    cache_dir = tmp_path_factory.mktemp("shimmy-cache")
    port = free_port()
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(cache_dir)}
    log = open(cache_dir / "gunicorn.log", "w")
    proc = subprocess.Popen([sys.executable, "-m", "gunicorn", "app:server", "--bind", f"127.0.0.1:{port}",
                             "--workers", "2", "--timeout", "120", "--no-control-socket"],
                            cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    deadline = time.time() + 60
    while True:
        try:
            with urllib.request.urlopen(base + "/api/v1/health", timeout=2) as resp:
                if resp.status == 200:
                    break
        except OSError:
            pass
        if proc.poll() is not None or time.time() > deadline:
            proc.kill()
            raise RuntimeError("gunicorn did not start: " + (cache_dir / "gunicorn.log").read_text()[-2000:])
        time.sleep(0.3)
    yield Server(base, cache_dir, proc)
    proc.terminate()
    try:
        proc.wait(timeout=15)
    except subprocess.TimeoutExpired:
        proc.kill()
    log.close()
