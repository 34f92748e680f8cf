"""``python -m shimmy serve``: the service as a team deploys it, nginx in front of gunicorn, both stopped together.

It writes nginx's configuration (:mod:`shimmy.service.nginx`) into a private run directory, starts
``gunicorn app:server`` (gunicorn.conf.py: the gthread worker) on a Unix socket there, which only the
proxy reaches, then nginx listening on ``--listen``. gunicorn is told where the proxy listens
(``SHIMMY_PROXY_LISTEN``: that address decides whether authentication is on by default) and to believe the
forwarding headers of the socket's clients only (``SHIMMY_TRUSTED_PROXY=unix``).

SIGTERM or SIGINT stops both gracefully at once (nginx: SIGQUIT, it finishes the requests in flight;
gunicorn: SIGTERM, its workers finish theirs and ``on_exit`` queues the running jobs again); SIGKILL goes
to whichever still runs after ``STOP_SECONDS``, and to whatever is left of their process groups (each runs
in its own: an nginx worker outlives a master that was killed); exit status 0. SIGHUP is passed to both
(gunicorn restarts its workers, nginx rereads its configuration). If either exits on its own, the other is
stopped the same way and the status is 1 (a restart policy then starts both again). As a container's first
process it also reaps any orphan handed to it.
"""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from . import nginx, settings

#: gunicorn's graceful_timeout (30 s) and a margin: then whatever still runs is killed.
STOP_SECONDS = 40.0
#: How long gunicorn may take to create its socket (it binds before loading the app).
BIND_SECONDS = 60.0
SOCKET_NAME = "gunicorn.sock"


class ServeError(RuntimeError):
    """The service cannot start as asked; the message says which option or what is missing."""


def default_run_dir() -> Path:
    """A private folder per user in the temporary directory (``/tmp/shimmy-serve-UID``)."""
    return Path(tempfile.gettempdir()) / f"shimmy-serve-{os.getuid()}"


def prepare_run_dir(run_dir: Path) -> Path:
    """``run_dir`` created 0700, refused if another user owns it or anyone else may write to it (the socket
    there is the app's only door: whoever may write there could stand in for the proxy)."""
    run_dir = run_dir.absolute()
    run_dir.mkdir(mode=0o700, parents=True, exist_ok=True)
    st = run_dir.stat()
    if st.st_uid != os.getuid():
        raise ServeError(f"--run-dir {run_dir} belongs to uid {st.st_uid}, not to this user (uid {os.getuid()}); "
                         "give a folder of your own")
    if st.st_mode & 0o077:
        raise ServeError(f"--run-dir {run_dir} may be read or written by others (mode {stat.S_IMODE(st.st_mode):o}); "
                         "chmod 700 it or give another folder")
    return run_dir


def gunicorn_command(socket_path: Path, workers: int) -> list[str]:
    return [sys.executable, "-m", "gunicorn", "app:server", "--bind", f"unix:{socket_path}", "--workers", str(workers),
            "--timeout", str(settings.REQUEST_SECONDS), "--no-control-socket"]


class AccessLogRelay:
    """nginx's access log onto serve's standard output, through a pipe of serve's own: nginx (the same user)
    may open its write end (``/dev/fd/N``), whereas it may not reopen a standard output that the container
    runtime made as root (``/dev/stdout``: permission denied)."""

    def __init__(self) -> None:
        self.read_fd, self.write_fd = os.pipe()
        self.thread = threading.Thread(target=self._copy, name="access-log", daemon=True)
        self.thread.start()

    @property
    def path(self) -> str:
        return f"/dev/fd/{self.write_fd}"

    def handed_over(self) -> None:
        """Close serve's copy of the write end once nginx holds it (the relay ends when nginx does)."""
        os.close(self.write_fd)

    def _copy(self) -> None:
        with open(self.read_fd, "rb", buffering=0) as source:
            while chunk := source.read(65536):
                sys.stdout.buffer.write(chunk)
                sys.stdout.buffer.flush()


class Supervisor:
    """gunicorn and nginx as child processes, reaped here; a stop request from a signal handler."""

    def __init__(self) -> None:
        self.children: dict[str, subprocess.Popen] = {}
        self.status: dict[str, int] = {}
        self.stop_signal: int | None = None
        self.hangup = False

    def start(self, name: str, argv: list[str], env: dict[str, str], cwd: Path, pass_fds: tuple[int, ...] = ()) -> None:
        try:  # its own process group: it and its workers
            proc = subprocess.Popen(argv, env=env, cwd=cwd, process_group=0, pass_fds=pass_fds)
        except OSError as exc:
            raise ServeError(f"cannot start {name} ({argv[0]}): {exc}") from exc
        self.children[name] = proc

    def reap(self) -> None:
        """Collect every ended child (ours, and orphans given to the first process of a container)."""
        while True:
            try:
                pid, wait_status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return
            if pid == 0:
                return
            for name, proc in self.children.items():
                if proc.pid == pid:
                    self.status[name] = proc.returncode = os.waitstatus_to_exitcode(wait_status)

    def running(self) -> list[str]:
        return [name for name in self.children if name not in self.status]

    def signal(self, name: str, sig: int) -> None:
        """``sig`` to child ``name`` if it still runs."""
        if name in self.children and name not in self.status:
            try:
                os.kill(self.children[name].pid, sig)
            except ProcessLookupError:
                pass

    def kill_group(self, name: str) -> None:
        """SIGKILL to whatever is left of child ``name``'s process group (the workers of a master that died)."""
        try:
            os.killpg(self.children[name].pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass

    def on_signal(self, signum, _frame) -> None:
        if signum == signal.SIGHUP:
            self.hangup = True
        elif self.stop_signal is None:
            self.stop_signal = signum

    def stop(self) -> None:
        """Both stopped gracefully (each stops its own workers), killed after STOP_SECONDS; then nothing left of
        their process groups (an nginx worker outlives a master that was killed, holding the port)."""
        for name in self.status:
            self.kill_group(name)
        self.signal("nginx", signal.SIGQUIT)
        self.signal("gunicorn", signal.SIGTERM)
        deadline = time.monotonic() + STOP_SECONDS
        while self.running() and time.monotonic() < deadline:
            time.sleep(0.1)
            self.reap()
        for name in self.running():
            print(f"shimmy serve: {name} still running after {STOP_SECONDS:g} s; killed", file=sys.stderr, flush=True)
        for name in self.children:
            self.kill_group(name)
        while self.running():
            time.sleep(0.05)
            self.reap()


def serve(listen: str, run_dir: Path | None = None, workers: int = 2, app_dir: Path | None = None,
          access_log: str = "-") -> int:
    """Run nginx on ``listen`` in front of gunicorn (``workers`` workers, ``app:server`` from ``app_dir``,
    default the current folder) until a signal or either ends; the exit status (ServeError before starting).
    nginx's access log goes to ``access_log``: a file, ``off``, or ``-`` (serve's standard output)."""
    listen = nginx.parse_listen(listen)
    if not 1 <= workers <= 64:
        raise ServeError(f"--workers={workers} is out of range; allowed: 1 to 64 gunicorn workers")
    app_dir = (app_dir or Path.cwd()).absolute()
    if not (app_dir / "app.py").is_file():
        raise ServeError(f"--app-dir {app_dir} holds no app.py (the workbench: run from the repository or /app in "
                         "the image)")
    executable = nginx.binary()
    if executable is None:
        raise ServeError("nginx is not installed (it holds slow clients in front of gunicorn): apt-get install "
                         "nginx on Debian, or run gunicorn alone on loopback for one user (README)")
    os.environ["SHIMMY_PROXY_LISTEN"] = listen
    os.environ["SHIMMY_TRUSTED_PROXY"] = "unix"
    mode = settings.auth_mode([listen])  # AuthSettingError: refused before anything starts, as gunicorn would
    run_dir = prepare_run_dir(run_dir or default_run_dir())
    socket_path = run_dir / SOCKET_NAME
    socket_path.unlink(missing_ok=True)  # left by a server that was killed
    conf = run_dir / "nginx.conf"
    relay = AccessLogRelay() if access_log == "-" else None
    conf.write_text(nginx.render(listen, f"unix:{socket_path}", run_dir,
                                 access_log=relay.path if relay else access_log))

    supervisor = Supervisor()
    for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(sig, supervisor.on_signal)
    env = dict(os.environ)
    print(f"shimmy serve: nginx on {listen} in front of gunicorn ({workers} workers) on unix:{socket_path}; "
          f"authentication {mode}", file=sys.stderr, flush=True)
    supervisor.start("gunicorn", gunicorn_command(socket_path, workers), env, app_dir)
    problem = _start_nginx(supervisor, executable, socket_path, conf, env, app_dir, relay)
    while problem is None and supervisor.stop_signal is None and len(supervisor.running()) == 2:
        if supervisor.hangup:
            supervisor.hangup = False
            supervisor.signal("gunicorn", signal.SIGHUP)
            supervisor.signal("nginx", signal.SIGHUP)
        time.sleep(0.2)
        supervisor.reap()
    ended = dict(supervisor.status)
    for name, code in ended.items():
        problem = f"{name} exited with status {code}"
    if problem is not None:
        print(f"shimmy serve: {problem}; stopping the rest", file=sys.stderr, flush=True)
    supervisor.stop()
    socket_path.unlink(missing_ok=True)
    if relay:
        relay.thread.join(timeout=2)  # the last lines nginx logged
    if problem is None:
        print(f"shimmy serve: stopped by {signal.Signals(supervisor.stop_signal).name}", file=sys.stderr, flush=True)
        return 0
    return 1


def _start_nginx(supervisor: Supervisor, executable: str, socket_path: Path, conf: Path, env: dict[str, str],
                 app_dir: Path, relay: AccessLogRelay | None) -> str | None:
    """nginx started once gunicorn has made its socket; what went wrong instead (None if nothing did, or if a
    stop was asked for meanwhile)."""
    deadline = time.monotonic() + BIND_SECONDS
    while not socket_path.exists():
        supervisor.reap()
        if supervisor.stop_signal is not None or "gunicorn" in supervisor.status:
            return None  # the caller says why
        if time.monotonic() > deadline:
            return f"gunicorn did not create {socket_path} within {BIND_SECONDS:g} s"
        time.sleep(0.05)
    try:
        supervisor.start("nginx", nginx.command(executable, socket_path.parent, conf), env, app_dir,
                         (relay.write_fd,) if relay else ())
    except ServeError as exc:
        return str(exc)
    finally:
        if relay:
            relay.handed_over()
    return None
