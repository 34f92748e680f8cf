"""Real servers for the service tests: gunicorn serving app:server on a loopback port, alone or behind
nginx as ``python -m shimmy serve`` runs them (the image's command)."""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


#: The longest modules, longest first (measured: pytest --durations=0). Under pytest-xdist (the README's
#: ``-n 2 --dist loadscope --no-loadscope-reorder``) each module goes whole to one worker, in collection
#: order: the longest ones start first and the short ones fill the gaps at the end. Tests keep their
#: order within a module; a module not listed keeps its place after these.
LONGEST_FIRST = [
    "tests/service/test_image_build.py",
    "tests/analyses/maps/test_warm_map.py",
    "tests/analyses/maps/test_stability_map.py",
    "tests/ui/test_browser.py",
    "tests/ui/test_browser_workbench.py",
    "tests/cli/test_cli.py",
    "tests/service/test_api.py",
    "tests/cli/test_cli_cache.py",
    "tests/service/test_neighbours.py",
    "tests/test_docs.py",
    "tests/analyses/core/test_executors.py",
    "tests/ui/test_browser_live_map.py",
    "tests/analyses/diagrams/test_bifurcation.py",
    "tests/analyses/decisions/test_optimise.py",
    "tests/ui/test_browser_design.py",
    "tests/analyses/diagrams/test_gear_cycle_curves.py",
    "tests/ui/test_browser_designs.py",
    "tests/analyses/decisions/test_min_shimmy_curve.py",
    "tests/analyses/decisions/test_studies.py",
    "tests/analyses/decisions/test_study_curves.py",
    "tests/service/test_reliability.py",
    "tests/ui/test_browser_ground_run.py",
    "tests/analyses/ground/test_ground_run.py",
]


#: Every compiled kernel the analyses use (integrator, field and Jacobian, collocation, condensed LU), run
#: once so that numba's on-disk cache holds them: about 40 s of compiling in a fresh checkout, 2 s to load
#: them from the cache afterwards.
WARM_KERNELS = """
import shimmy
from shimmy.analyses.diagrams.bifurcation import bifurcation
from shimmy.analyses.diagrams.hopf_curves import hopf_curves
shimmy.simulate("nes_pd", 30, 150e3, t_end=1)
shimmy.ground_run("original", "taxi")
shimmy.hopf_points("nes", 150e3)
bifurcation("original", 150e3, v_range=(5.0, 16.0))
hopf_curves("nes", v_range=(1.0, 200.0), fz_range=(1.0e5, 2.0e5), n_slices=3)
"""


def pytest_configure(config):
    """Under xdist, the controller warms numba's cache before the workers start: in a fresh checkout
    each worker, its process pools and its servers would otherwise compile the same kernels at once."""
    if getattr(config.option, "numprocesses", None) and not hasattr(config, "workerinput"):
        done = subprocess.run([sys.executable, "-c", WARM_KERNELS], cwd=ROOT, capture_output=True, text=True,
                              timeout=900)
        if done.returncode != 0:  # the tests that use these kernels fail on their own, naming the error
            config.issue_config_time_warning(pytest.PytestWarning(
                "warming numba's cache failed: " + done.stderr[-1000:]), stacklevel=2)


def pytest_collection_modifyitems(config, items):
    rank = {path: i for i, path in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    """A failed test that used a server says what the server was doing: its jobs (analysis,
    configuration, status, message, times) and the end of its log, so that a wait that timed out
    on a loaded machine names why."""
    report = yield
    if report.failed and call.when == "call":
        try:  # a report of a failure must not fail (an error here would end the xdist worker)
            for server in [v for v in (getattr(item, "funcargs", None) or {}).values() if isinstance(v, Server)]:
                report.sections.append((f"server {server.base}: its jobs", _jobs_summary(server)))
                log = server.cache_dir / "gunicorn.log"
                tail = log.read_text(errors="replace")[-3000:] if log.exists() else "(no log)"
                report.sections.append((f"server {server.base}: the end of its log", tail))
        except Exception as exc:  # noqa: BLE001
            report.sections.append(("server state", f"(unavailable: {type(exc).__name__}: {exc})"))
    return report


def _jobs_summary(server: "Server") -> str:
    try:
        from shimmy.service import jobs

        found = sorted(server.job_records().values(), key=lambda j: j.get("created", 0))
        with server.cache_env():
            running = dict(jobs.store().get("running", {}))
    except Exception as exc:  # noqa: BLE001 - a report of a failure must not fail
        return f"(job store unreadable: {type(exc).__name__}: {exc})"
    from shimmy.model.parameters import Parameters

    base, now = Parameters().to_dict(), time.time()
    lines = [f"{len(found)} jobs, running slots: {sorted(running)}"]
    for j in found[-40:]:
        request = j.get("request") or {}
        lines.append(f"{str(j.get('id'))[:8]} {j.get('analysis')} {request.get('config', '')} {j.get('status')} "
                     f"created {now - j.get('created', now):.1f} s ago, updated {now - j.get('updated', now):.1f} s "
                     f"ago: {j.get('message')} {j.get('error') or ''}; design changes "
                     f"{ {k: v for k, v in (request.get('params') or {}).items() if base.get(k) != v} }")
    return "\n".join(lines)


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

    def job_records(self) -> dict[str, dict]:
        """Every job its job store holds, by id (queued, running and finished ones)."""
        from shimmy.service import jobs

        with self.cache_env():
            s = jobs.store()
            found = (s.get(k) for k in list(s) if isinstance(k, tuple) and len(k) == 2 and k[0] == "job")
            return {j["id"]: j for j in found if j is not None}

    def request(self, method: str, path: str, body=None, raw: bytes | None = None, timeout: float = 60.0,
                headers: dict[str, str] | None = None):
        """(status, headers, parsed JSON or text) of one request (Content-Type JSON unless ``headers`` say)."""
        data = raw if raw is not None else (None if body is None else json.dumps(body).encode())
        sent = {"Content-Type": "application/json"} if data is not None else {}
        req = urllib.request.Request(self.base + path, data=data, method=method, headers={**sent, **(headers or {})})
        try:
            with urllib.request.urlopen(req, timeout=timeout) as resp:
                status, headers, text = resp.status, resp.headers, resp.read().decode()
        except urllib.error.HTTPError as exc:
            status, headers, text = exc.code, exc.headers, exc.read().decode()
        try:
            return status, headers, json.loads(text)
        except ValueError:
            return status, headers, text


def start_server(cache_dir: Path, env: dict[str, str] | None = None, workers: int = 2) -> Server:
    """gunicorn app:server on a free loopback port with ``cache_dir`` (and ``env``), once it answers."""
    port = free_port()
    full_env = {**os.environ, "SHIMMY_CACHE_DIR": str(cache_dir), **(env or {})}
    log = open(cache_dir / "gunicorn.log", "w")
    proc = subprocess.Popen([sys.executable, "-m", "gunicorn", "app:server", "--bind", f"127.0.0.1:{port}",
                             "--workers", str(workers), "--timeout", "120", "--no-control-socket"],
                            cwd=ROOT, env=full_env, stdout=log, stderr=subprocess.STDOUT)
    server = Server(_healthy(f"http://127.0.0.1:{port}", proc, cache_dir, "gunicorn"), cache_dir, proc)
    server.log = log
    return server


def _healthy(base: str, proc: subprocess.Popen, cache_dir: Path, what: str) -> str:
    """``base`` once its health answers 200 (within 60 s); the process killed and its log quoted if it ends
    or does not answer."""
    deadline = time.time() + 60
    while True:
        try:
            with urllib.request.urlopen(base + "/api/v1/health", timeout=2) as resp:
                if resp.status == 200:
                    return base
        except OSError:
            pass
        if proc.poll() is not None or time.time() > deadline:
            proc.kill()
            raise RuntimeError(f"{what} did not start: " + (cache_dir / "gunicorn.log").read_text()[-2000:])
        time.sleep(0.3)


def stop_server(server: Server, timeout: float = 15) -> None:
    server.proc.terminate()
    try:
        server.proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        server.proc.kill()
        server.proc.wait(timeout=15)
    server.log.close()


#: Held around apt-get by every test that installs a Debian package (here, tests/ui/browser.py) and by
#: scripts/build_image_offline.sh: two xdist workers on a fresh machine would otherwise run apt-get at once,
#: and one fails on apt's own lock.
APT_LOCK = "/tmp/shimmy-tests-apt.lock"


def apt_install(packages: list[str], present) -> None:
    """Debian ``packages`` installed with apt-get unless ``present()`` (under APT_LOCK); pytest.fail if that
    is needed and cannot be done here (not root, no apt-get)."""
    if present():
        return
    if os.geteuid() != 0 or not shutil.which("apt-get"):
        pytest.fail(f"Debian {', '.join(packages)} needed and cannot be installed here (not root, or no apt-get)")
    with open(APT_LOCK, "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # another worker may be installing right now
        if present():
            return
        env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
        subprocess.run(["apt-get", "update", "-qq"], check=True, env=env, timeout=600)
        subprocess.run(["apt-get", "install", "-y", "-qq", *packages], check=True,
                       env=env, timeout=600)


def ensure_nginx() -> str:
    """nginx's executable, Debian's package installed first when missing."""
    from shimmy.service import nginx

    apt_install(["nginx"], lambda: nginx.binary() is not None)
    return nginx.binary()


def start_proxied_server(cache_dir: Path, env: dict[str, str] | None = None, workers: int = 1,
                         access_log: str | None = None) -> Server:
    """``python -m shimmy serve``: nginx on a free loopback port in front of gunicorn (``workers`` workers) on a
    Unix socket in ``cache_dir/run``, once health answers through both. ``proc`` is the supervisor; nginx's
    access log is ``access_log`` (default ``run/access.log``; ``-``: serve's output), everything else goes to
    ``gunicorn.log``."""
    ensure_nginx()
    port = free_port()
    run_dir = cache_dir / "run"
    full_env = {**os.environ, "SHIMMY_CACHE_DIR": str(cache_dir), **(env or {})}
    log = open(cache_dir / "gunicorn.log", "w")
    proc = subprocess.Popen([sys.executable, "-m", "shimmy", "serve", "--listen", f"127.0.0.1:{port}", "--workers",
                             str(workers), "--run-dir", str(run_dir), "--access-log",
                             access_log or str(run_dir / "access.log")],
                            cwd=ROOT, env=full_env, stdout=log, stderr=subprocess.STDOUT)
    server = Server(_healthy(f"http://127.0.0.1:{port}", proc, cache_dir, "shimmy serve"), cache_dir, proc)
    server.log, server.run_dir = log, run_dir
    return server


@pytest.fixture(scope="session", autouse=True)
def session_cache(tmp_path_factory):
    """SHIMMY_CACHE_DIR of the session: a fresh result cache for every test, command line and server that does
    not name its own, so that no test reads a result stored by other code of the same version (the cache
    keys by version, not by commit) and the user's own cache is left alone."""
    patch = pytest.MonkeyPatch()
    patch.setenv("SHIMMY_CACHE_DIR", str(tmp_path_factory.mktemp("session-cache")))
    yield
    patch.undo()


@pytest.fixture(scope="session")
def server(tmp_path_factory):
    """gunicorn app:server with 2 workers and a fresh shared cache directory."""
    srv = start_server(tmp_path_factory.mktemp("shimmy-cache"))
    yield srv
    stop_server(srv)


@pytest.fixture(scope="session")
def browsers():
    """The Chromium instances of the browser modules (tests/ui/browser.py), by profile, window and
    downloads folder: each started once per session and quit at its end."""
    pool: dict = {}
    yield pool
    for driver in pool.values():
        driver.quit()


def process_group(pid):
    """The process group of ``pid``, or None once the process is gone."""
    try:
        return os.getpgid(pid)
    except OSError:
        return None
