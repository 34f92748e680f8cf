"""Slow clients, oversized bodies and the client's address, against the service as a team deploys it:
``python -m shimmy serve`` (the image's command) started here on loopback, nginx (Debian's package,
installed when missing) in front of gunicorn's gthread worker on a Unix socket.

The proxy's deadlines are 3 s here and gunicorn has 8 threads, so that a slow client that reached
gunicorn would soon show (a control connects to gunicorn's socket directly and does stall it). Every
count and wait is bounded; polls run until a condition holds or a generous deadline. Figures (times,
counts) are printed for the closing note (pytest -s shows them).
"""

from __future__ import annotations

import concurrent.futures
import http.client
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import time
import urllib.parse

import psutil
import pytest

from conftest import ROOT, ensure_nginx, free_port, start_proxied_server, stop_server
from test_reliability import named
from test_team import bearer, make_tokens

pytestmark = pytest.mark.slow

DEADLINE = 3.0  # SHIMMY_HEADER_READ_SECONDS, SHIMMY_BODY_READ_SECONDS and SHIMMY_KEEPALIVE_SECONDS here
THREADS = 8
LIMITS = {"SHIMMY_HEADER_READ_SECONDS": "3", "SHIMMY_BODY_READ_SECONDS": "3", "SHIMMY_KEEPALIVE_SECONDS": "3",
          "SHIMMY_WEB_THREADS": str(THREADS), "SHIMMY_AUTH": "token", "SHIMMY_LOGIN_ATTEMPTS_PER_MINUTE": "5",
          "GUNICORN_CMD_ARGS": "--access-logfile -"}
HOPF = {"config": "nes", "Fz": 150000, "v_max": 200}


@pytest.fixture(scope="module")
def proxied(tmp_path_factory):
    cache_dir = tmp_path_factory.mktemp("proxied")
    made = make_tokens(cache_dir, {"alice": "compute"})
    server = start_proxied_server(cache_dir, LIMITS)
    server.token = made["alice"][1]
    server.auth = bearer(server.token)
    yield server
    if server.proc.poll() is None:
        stop_server(server, timeout=45)


def _address(server) -> tuple[str, int]:
    parts = urllib.parse.urlsplit(server.base)
    return parts.hostname, parts.port


def connect(server, source: str | None = None) -> socket.socket:
    return socket.create_connection(_address(server), timeout=10, source_address=(source, 0) if source else None)


def health_times(server, n: int = 10, timeout: float = 30) -> list[float]:
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        status, _, _ = server.request("GET", "/api/v1/health", timeout=timeout)
        out.append(time.perf_counter() - t0)
        assert status == 200
    return out


def open_slow_clients(base: str, n: int) -> list[socket.socket]:
    """``n`` connections that never finish their request: half stop inside the headers, half send
    complete headers announcing 1000 body bytes and then one."""
    host, port = base.removeprefix("http://").split(":")
    socks = []
    for k in range(n):
        s = socket.create_connection((host, int(port)), timeout=10)
        s.sendall(b"POST /api/v1/simulate HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Content-Length: 1000\r\n\r\n{" if k % 2 else b"GET /api/v1/health HTTP/1.1\r\nHost: x\r\nX-Slow")
        socks.append(s)
    return socks


def closed_by_server(s: socket.socket) -> bool:
    """Whether the server closed (or reset) the connection; data it sent before closing is read and dropped."""
    s.settimeout(0.01)
    try:
        while True:
            data = s.recv(65536)
            if not data:
                return True
    except TimeoutError:
        return False
    except OSError:
        return True


def wait_closed(socks: list[socket.socket], timeout: float) -> dict[int, float]:
    """{index: seconds from now until the server closed it} for the connections closed within ``timeout``."""
    t0 = time.monotonic()
    closed: dict[int, float] = {}
    while len(closed) < len(socks) and time.monotonic() - t0 < timeout:
        for i, s in enumerate(socks):
            if i not in closed and closed_by_server(s):
                closed[i] = time.monotonic() - t0
        time.sleep(0.05)
    return closed


def test_nginx_takes_the_configuration_rendered_from_the_settings(tmp_path, monkeypatch):
    from shimmy.service import nginx, settings

    monkeypatch.setattr(settings, "HEADER_READ_SECONDS", 7.0)
    monkeypatch.setattr(settings, "BODY_READ_SECONDS", 2.5)
    conf = nginx.render("127.0.0.1:8050", f"unix:{tmp_path}/gunicorn.sock", tmp_path, access_log="off")
    for line in ("client_header_timeout 7s;", "client_body_timeout 2500ms;", "send_timeout 30s;",
                 f"client_max_body_size {settings.MAX_BODY_BYTES};", "proxy_request_buffering on;",
                 "proxy_buffering on;", "keepalive_timeout 15s;", "keepalive_requests 1000;",
                 "proxy_set_header X-Forwarded-For $remote_addr;", "listen 127.0.0.1:8050;", "daemon off;"):
        assert line in conf, line
    (tmp_path / "nginx.conf").write_text(conf)
    done = subprocess.run([*nginx.command(ensure_nginx(), tmp_path, tmp_path / "nginx.conf"), "-t"],
                          capture_output=True, text=True, timeout=30)
    assert done.returncode == 0 and "test is successful" in done.stderr, done.stderr
    # With no gunicorn behind it (starting, restarting), the proxy answers 503 in JSON with Retry-After.
    port = free_port()
    (tmp_path / "nginx.conf").write_text(nginx.render(f"127.0.0.1:{port}", f"unix:{tmp_path}/none.sock", tmp_path,
                                                      access_log="off"))
    alone = subprocess.Popen(nginx.command(ensure_nginx(), tmp_path, tmp_path / "nginx.conf"), stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 20
        while True:
            try:
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
                conn.request("GET", "/api/v1/health")
                resp = conn.getresponse()
                break
            except OSError:
                assert time.monotonic() < deadline and alone.poll() is None, "nginx did not start"
                time.sleep(0.1)
        answer = json.loads(resp.read())
        assert resp.status == 503 and resp.headers["Retry-After"] == "5" and "not answering" in answer["error"]
    finally:
        alone.terminate()
        alone.wait(timeout=20)
    for bad, option in (("0.0.0.0:99999", "--listen"), ("8050; user root", "--listen"), ("[::g]:1", "--listen")):
        with pytest.raises(nginx.ProxyConfigError, match=option):
            nginx.render(bad, "unix:/tmp/x.sock", tmp_path)
    with pytest.raises(nginx.ProxyConfigError, match="--upstream"):
        nginx.render("8050", "unix:/tmp/x.sock;\n}", tmp_path)
    with pytest.raises(nginx.ProxyConfigError, match="--run-dir"):
        nginx.render("8050", "unix:/tmp/x.sock", "/tmp/a b")


def test_fifty_slow_clients_do_not_stall_the_service_and_are_closed(proxied):
    socks = open_slow_clients(proxied.base, 50)
    try:
        health, hopf = [], []
        for k in range(10):
            health += health_times(proxied, 1)
            t0 = time.perf_counter()
            status, _, _ = proxied.request("POST", "/api/v1/hopf", {**HOPF, "Fz": 150000 + k}, headers=proxied.auth)
            hopf.append(time.perf_counter() - t0)
            assert status == 200
        closed = wait_closed(socks, 30)
        print(f"\n50 slow clients: health median {1e3 * statistics.median(health):.1f} ms, max "
              f"{1e3 * max(health):.1f} ms; uncached POST /hopf median {1e3 * statistics.median(hopf):.1f} ms; "
              f"closed by the proxy: {len(closed)} of 50, the last {max(closed.values(), default=0):.1f} s after "
              f"the requests")
        assert statistics.median(health) < 1.0 and max(health) < 5.0
        assert len(closed) == 50
    finally:
        for s in socks:
            s.close()


def test_trickled_headers_are_cut_at_the_header_deadline_and_never_reach_gunicorn(proxied):
    """Slowloris: headers sent a byte every 0.25 s. Through the proxy they hold no thread and are closed at the
    header deadline however busy they look; sent to gunicorn's socket directly, 8 of them take its 8 threads."""
    host, port = _address(proxied)
    head = b"GET /api/v1/health HTTP/1.1\r\nHost: x\r\n" + b"X-Slow: " + b"a" * 200
    socks = [socket.create_connection((host, port), timeout=10) for _ in range(3 * THREADS)]
    opened = time.monotonic()
    closed_at: dict[int, float] = {}
    health = []
    try:
        for k in range(len(head)):
            for i, s in enumerate(socks):
                if i in closed_at:
                    continue
                try:
                    s.sendall(head[k:k + 1])
                except OSError:
                    closed_at[i] = time.monotonic() - opened
            if k % 4 == 0:
                health += health_times(proxied, 1, timeout=10)
            if len(closed_at) == len(socks) or time.monotonic() - opened > 20:
                break
            time.sleep(0.25)
        for i, s in enumerate(socks):  # a reset may show on the next read rather than on a send
            if i not in closed_at and closed_by_server(s):
                closed_at[i] = time.monotonic() - opened
    finally:
        for s in socks:
            s.close()
    print(f"\nslowloris through the proxy: {len(socks)} connections trickling headers closed after "
          f"{min(closed_at.values(), default=0):.1f}-{max(closed_at.values(), default=0):.1f} s (deadline "
          f"{DEADLINE:g} s); health meanwhile median {1e3 * statistics.median(health):.1f} ms, max "
          f"{1e3 * max(health):.1f} ms")
    assert len(closed_at) == len(socks)
    assert DEADLINE - 0.5 <= min(closed_at.values()) and max(closed_at.values()) <= DEADLINE + 3
    assert statistics.median(health) < 1.0 and max(health) < 5.0

    # The control: the same trickle on gunicorn's own socket takes its threads, and health through the proxy waits.
    direct = []
    try:
        for _ in range(THREADS):
            s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            s.settimeout(10)
            s.connect(str(proxied.run_dir / "gunicorn.sock"))
            s.sendall(head[:40])
            direct.append(s)
        time.sleep(1.0)
        with pytest.raises(OSError):  # a timeout: no thread is free to answer
            proxied.request("GET", "/api/v1/health", timeout=3)
    finally:
        for s in direct:
            s.close()
    assert max(health_times(proxied, 3)) < 5.0
    print(f"the same on gunicorn's socket directly: {THREADS} connections stalled health for over 3 s")


def test_a_body_never_finished_is_closed_without_reaching_the_app(proxied):
    with connect(proxied) as s:
        t0 = time.perf_counter()
        s.sendall(b"POST /api/v1/simulate HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Content-Length: 1000\r\n\r\n{\"config\": \"nes\"")
        closed = wait_closed([s], 20)
        elapsed = time.perf_counter() - t0
    print(f"\nbody stopped after 16 of 1000 bytes: closed by the proxy after {elapsed:.1f} s (deadline {DEADLINE:g} s)")
    assert closed and DEADLINE - 0.5 <= elapsed <= DEADLINE + 3
    time.sleep(0.5)
    assert " 408 " in (proxied.run_dir / "access.log").read_text()  # nginx logs what it cut
    app_log = (proxied.cache_dir / "gunicorn.log").read_text(errors="replace")
    assert '] "GET /api/v1/health' in app_log  # gunicorn's access log, which would have it:
    assert '] "POST /api/v1/simulate' not in app_log  # gunicorn never saw it


def test_a_trickled_body_holds_no_gunicorn_thread_and_arrives_whole(proxied):
    """Three times as many bodies as gunicorn has threads, each sent in 5 parts 1 s apart (5 s in all, longer
    than the 3 s deadline, which bounds a pause, not the whole): health stays prompt, each request is answered
    (from the cache, so that the quick computations' admission control does not refuse any)."""
    question = {**HOPF, "Fz": 160000}
    assert proxied.request("POST", "/api/v1/hopf", question, headers=proxied.auth)[0] == 200  # cached: no slot taken
    body = json.dumps(question).encode()
    body += b" " * (2000 - len(body))
    head = (f"POST /api/v1/hopf HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nAuthorization: Bearer "
            f"{proxied.token}\r\nConnection: close\r\nContent-Length: {len(body)}\r\n\r\n").encode()
    socks = [connect(proxied) for _ in range(3 * THREADS)]
    health = []
    t0 = time.perf_counter()
    try:
        for s in socks:
            s.sendall(head)
        for part in range(5):
            for s in socks:
                s.sendall(body[400 * part:400 * (part + 1)])
            health += health_times(proxied, 2)
            if part < 4:
                time.sleep(1.0)
        answers = []
        for s in socks:
            s.settimeout(60)
            data = b""
            while chunk := s.recv(65536):
                data += chunk
            answers.append(data)
    finally:
        for s in socks:
            s.close()
    statuses = [a.split(b" ", 2)[1] for a in answers]
    print(f"\n{len(socks)} bodies trickled over {time.perf_counter() - t0:.1f} s: answers {sorted(set(statuses))}; "
          f"health meanwhile median {1e3 * statistics.median(health):.1f} ms, max {1e3 * max(health):.1f} ms")
    assert statuses == [b"200"] * len(socks)
    assert statistics.median(health) < 1.0 and max(health) < 5.0


def test_an_oversized_body_is_refused_413_by_the_proxy_in_the_apis_shape(proxied):
    from shimmy.service import settings

    limit = settings.MAX_BODY_BYTES
    status, headers, answer = proxied.request("POST", "/api/v1/hopf", raw=b" " * (limit + 1), headers=proxied.auth)
    assert status == 413 and named(answer) and answer["field"] == "body" and str(limit) in answer["error"]
    assert headers["Content-Type"] == "application/json"
    # chunked, no length announced: cut when it passes the limit
    with connect(proxied) as s:
        s.sendall(b"POST /api/v1/hopf HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Transfer-Encoding: chunked\r\n\r\n")
        try:
            for _ in range(limit // 8192 + 2):
                s.sendall(b"2000\r\n" + b" " * 8192 + b"\r\n")
        except OSError:
            pass  # the proxy may answer and close before the last chunks
        s.settimeout(10)
        head = s.recv(65536)
    assert head.startswith(b"HTTP/1.1 413"), head[:200]
    # at the limit exactly: passed on, answered by the app
    body = json.dumps({**HOPF, "Fz": 161000}).encode()
    status, _, answer = proxied.request("POST", "/api/v1/hopf", raw=body + b" " * (limit - len(body)),
                                        headers=proxied.auth)
    assert status == 200, answer
    print(f"\nbody limit {limit} bytes: {limit + 1} announced -> 413 from the proxy (JSON naming body), chunked "
          f"beyond -> 413, {limit} -> 200 from the app")


def test_a_request_line_or_header_too_long_is_refused_by_the_proxy_in_the_apis_shape(proxied):
    """Beyond nginx's header buffers (8 kB a line): 414 for the request line, 431 for a header, each in the
    API's JSON shape naming what was too long (nginx's own HTML page before); just under them, the app
    answers; the pages behind those answers are not reachable from outside."""
    status, headers, answer = proxied.request("GET", "/api/v1/jobs?limit=" + "9" * 9000, headers=proxied.auth)
    assert status == 414 and named(answer) and answer["field"] == "request line" and "8192" in answer["error"]
    assert headers["Content-Type"] == "application/json"
    status, headers, answer = proxied.request("GET", "/api/v1/health", headers={"X-Padding": "p" * 9000})
    assert status == 431 and named(answer) and answer["field"] == "headers", answer
    assert headers["Content-Type"] == "application/json"
    status, _, answer = proxied.request("GET", "/api/v1/health", headers={"X-Padding": "p" * 7000})
    assert status == 200, answer
    for inside in ("/__shimmy_request_line_too_long", "/__shimmy_headers_too_large"):
        assert proxied.request("GET", inside)[0] == 404


def test_many_idle_connections_leave_the_service_prompt_and_are_closed(proxied):
    idle = [connect(proxied) for _ in range(300)]  # connected, nothing sent
    kept = []
    for _ in range(50):  # one request each, then kept alive and left idle
        s = connect(proxied)
        s.sendall(b"GET /api/v1/health HTTP/1.1\r\nHost: x\r\n\r\n")
        s.settimeout(10)
        assert s.recv(65536).startswith(b"HTTP/1.1 200")
        kept.append(s)
    try:
        health = health_times(proxied, 20)
        closed = wait_closed(idle + kept, 20)
    finally:
        for s in idle + kept:
            s.close()
    print(f"\n300 idle and 50 kept-alive connections: health median {1e3 * statistics.median(health):.1f} ms, max "
          f"{1e3 * max(health):.1f} ms; {len(closed)} of 350 closed by the proxy, the last "
          f"{max(closed.values(), default=0):.1f} s after the health checks")
    assert statistics.median(health) < 1.0 and max(health) < 5.0
    assert len(closed) == 350


def _sign_in(server, source: str, spoof: str | None = None) -> int:
    host, port = _address(server)
    conn = http.client.HTTPConnection(host, port, timeout=30, source_address=(source, 0))
    headers = {"Content-Type": "application/x-www-form-urlencoded"}
    if spoof:
        headers.update({"X-Forwarded-For": spoof, "X-Real-IP": spoof, "Forwarded": f"for={spoof}"})
    try:
        conn.request("POST", "/login", urllib.parse.urlencode({"token": "shm_" + "W" * 43}), headers)
        resp = conn.getresponse()
        resp.read()
        return resp.status
    finally:
        conn.close()


def test_sign_in_attempts_count_per_client_address_which_no_client_can_choose(proxied):
    """Behind the proxy gunicorn sees every request come from its socket: the client's address is the one nginx
    forwards. A client that sends its own X-Forwarded-For (a new address each time) is still counted as itself and
    refused at the limit (5 a minute here); another client (127.0.0.2) is not."""
    statuses = []
    for k in range(12):  # the limit is 5 a minute (the minute may turn once meanwhile)
        statuses.append(_sign_in(proxied, "127.0.0.1", spoof=f"10.9.{k}.7"))
        if statuses[-1] == 429:
            break
    other = _sign_in(proxied, "127.0.0.2")
    print(f"\nsign-in through the proxy, a new X-Forwarded-For each time: {statuses}; from 127.0.0.2 then: {other}")
    assert statuses[-1] == 429 and set(statuses[:-1]) == {401} and len(statuses) <= 11
    assert other == 401
    log = (proxied.run_dir / "access.log").read_text()
    assert "127.0.0.2 - - " in log and "10.9." not in log and "shm_" not in log


def _tree(pid: int) -> list[psutil.Process]:
    return psutil.Process(pid).children(recursive=True)


def _alive(processes: list[psutil.Process]) -> list[int]:
    out = []
    for p in processes:
        try:
            if p.is_running() and p.status() != psutil.STATUS_ZOMBIE:
                out.append(p.pid)
        except psutil.NoSuchProcess:
            pass
    return out


def test_sigterm_stops_nginx_and_gunicorn_together(proxied):
    """Last in the module: it stops the module's server."""
    children = _tree(proxied.proc.pid)
    names = {p.pid: " ".join(p.cmdline()) for p in children}
    assert any("nginx: master" in c for c in names.values()) and any("gunicorn" in c for c in names.values())
    t0 = time.perf_counter()
    proxied.proc.send_signal(signal.SIGTERM)
    code = proxied.proc.wait(timeout=45)
    elapsed = time.perf_counter() - t0
    print(f"\nSIGTERM: serve exited {code} after {elapsed:.1f} s; of its {len(children)} processes (nginx, "
          f"gunicorn and their workers) left: {_alive(children)}")
    assert code == 0 and not _alive(children)
    assert not (proxied.run_dir / "gunicorn.sock").exists()
    with pytest.raises(OSError):
        socket.create_connection(_address(proxied), timeout=2)
    proxied.log.close()


def test_either_process_ending_stops_the_other(tmp_path):
    """With the image's access log (serve's own output, relayed from a pipe nginx may open as any user)."""
    server = start_proxied_server(tmp_path, {"SHIMMY_WEB_THREADS": "4"}, access_log="-")
    try:
        assert server.request("GET", "/api/v1/health?from=relay")[0] == 200
        time.sleep(0.5)
        assert '"GET /api/v1/health?from=relay HTTP/1.1" 200' in (tmp_path / "gunicorn.log").read_text()
        master = next(p for p in _tree(server.proc.pid) if "nginx: master" in " ".join(p.cmdline()))
        rest = [p for p in _tree(server.proc.pid) if p.pid != master.pid]
        master.kill()
        code = server.proc.wait(timeout=45)
        log = (tmp_path / "gunicorn.log").read_text(errors="replace")
        assert code == 1 and "nginx exited with status -9; stopping the rest" in log
        assert not _alive(rest)
    finally:
        if server.proc.poll() is None:
            stop_server(server, timeout=45)
        server.log.close()


def test_serve_refuses_what_it_cannot_do_before_starting_anything(tmp_path):
    env = {**os.environ, "SHIMMY_CACHE_DIR": str(tmp_path), "SHIMMY_AUTH": "none"}
    env.pop("SHIMMY_ALLOW_ANONYMOUS", None)
    port = free_port()

    def serve(*args, **extra):
        return subprocess.run([sys.executable, "-m", "shimmy", "serve", "--run-dir", str(tmp_path / "run"), *args],
                              cwd=ROOT, env={**env, **extra}, capture_output=True, text=True, timeout=60)

    done = serve("--listen", f"0.0.0.0:{port}")
    assert done.returncode == 2 and "SHIMMY_ALLOW_ANONYMOUS" in done.stderr
    assert not (tmp_path / "run").exists()  # nothing started, nothing written
    done = serve("--listen", "127.0.0.1:70000")
    assert done.returncode == 2 and "--listen='127.0.0.1:70000'" in done.stderr
    (tmp_path / "open").mkdir(mode=0o777)
    (tmp_path / "open").chmod(0o777)
    done = serve("--listen", f"127.0.0.1:{port}", "--run-dir", str(tmp_path / "open"))
    assert done.returncode == 2 and "--run-dir" in done.stderr and "chmod 700" in done.stderr
