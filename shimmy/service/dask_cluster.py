"""A Dask scheduler and workers on loopback, as separate processes (tests, benchmarks, a laptop).

``with loopback_cluster(n_workers=2) as address:`` starts ``dask scheduler`` and
``n_workers`` single-threaded ``dask worker`` processes bound to 127.0.0.1, waits until
every worker has registered and stops them all on exit. Point the package at it with
``SHIMMY_DASK_SCHEDULER=address`` or ``open_executor(scheduler=address)``.
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time
from typing import Iterator

STARTUP_S = 60.0


@contextlib.contextmanager
def loopback_cluster(n_workers: int = 2, log_dir: str | os.PathLike | None = None) -> Iterator[str]:
    from distributed import Client

    with contextlib.ExitStack() as stack:
        where = pathlib.Path(log_dir) if log_dir else pathlib.Path(stack.enter_context(tempfile.TemporaryDirectory()))
        scheduler_file = where / "scheduler.json"
        procs: list[subprocess.Popen] = []

        def start(args, log):
            procs.append(subprocess.Popen([sys.executable, "-m", *args], stdout=subprocess.DEVNULL,
                                          stderr=stack.enter_context(open(where / log, "w"))))

        try:
            start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                   "--scheduler-file", str(scheduler_file)], "scheduler.log")
            deadline = time.monotonic() + STARTUP_S
            address = None
            while address is None:
                if procs[0].poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError("the Dask scheduler did not start: " + (where / "scheduler.log").read_text())
                try:
                    address = json.loads(scheduler_file.read_text())["address"]
                except (OSError, ValueError, KeyError):
                    time.sleep(0.1)
            for k in range(n_workers):
                start(["distributed.cli.dask_worker", address, "--host", "127.0.0.1", "--no-nanny",
                       "--nthreads", "1", "--no-dashboard", "--name", f"worker-{k}"], f"worker-{k}.log")
            with Client(address, timeout=STARTUP_S) as client:
                client.wait_for_workers(n_workers, timeout=STARTUP_S)
            yield address
        finally:
            for p in procs[::-1]:
                p.terminate()
            for p in procs:
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
