#!/usr/bin/env bash
# Build the repository's Dockerfile, unchanged, without Docker or a container registry,
# then smoke-test the image.
#
#   1. buildah + debootstrap from Debian's packages (apt-get, if missing).
#   2. A Debian bookworm root filesystem made by debootstrap from the mirror this machine's
#      apt uses, with Debian's Python 3.11 (python3, python3-venv) in a venv at /opt/venv whose bin/ (python, pip)
#      is first on PATH: the stand-in for the official python:3.11-slim-bookworm image
#      (whose python/pip live in /usr/local/bin). A venv rather than the system python3
#      because Debian's python3 refuses `pip install` into it (PEP 668, EXTERNALLY-MANAGED).
#   3. That root filesystem committed to buildah's storage as python:3.11-slim-bookworm
#      (docker.io/library/... and localhost/...), so the Dockerfile's FROM resolves locally.
#   4. buildah build --isolation=chroot --pull=never (overlay storage where the kernel mounts an
#      overlay here, else vfs: see SHIMMY_STORAGE_DRIVER below), with the host's
#      CA bundle and the host's effective pip configuration (`pip config list`: files and
#      PIP_* variables, merged into one pip.conf) mounted, plus every local path that
#      configuration names (file:// indexes, find-links folders), so pip inside the build
#      reaches the same package indexes as pip on the host; likewise the host's apt settings
#      for the Dockerfile's apt-get (nginx) from the same Debian mirror as the base.
#   5. Smoke test in a container of the image: imports, numba cache warm, and (when the
#      image has app.py) its CMD on a loopback port (nginx in front of gunicorn) answering
#      /api/v1/health and stopping on SIGTERM; a Dask
#      scheduler + worker running shimmy.simulate when distributed is installed.
#
# Re-runs reuse the debootstrap root, the base image and buildah's layer cache.
# Environment:
#   SHIMMY_BUILD_WORK   work folder (default /var/tmp/shimmy-image-build): rootfs, storage
#   SHIMMY_IMAGE        tag of the built image (default localhost/shimmy:local)
#   SHIMMY_REBUILD_BASE=1  make the debootstrap root and the base image again
#   SHIMMY_SKIP_SMOKE=1    build only
#   SHIMMY_DEBIAN_MIRROR   Debian mirror for debootstrap (default: the one apt uses here)
#   SHIMMY_STORAGE_DRIVER  buildah's storage driver, overlay or vfs (default: overlay if a test overlay
#                          mounts in the work folder, else vfs). Measured from scratch on a 2-core machine:
#                          the build 65 s with overlay against 107 s with vfs (vfs copies the whole root
#                          for every layer and every container), the whole script 154 s against 200 s.
#                          Each driver has its own storage folder (storage-overlay, storage-vfs).
# Disk: with vfs about 7 GB in the work folder (a full copy of every layer: ~0.8 GB each; overlay
# keeps only each layer's changes); the images an earlier build left untagged are removed before each
# build (they grew the folder by ~7 GB a build until the disk was full: 64 GB after a day of runs);
# rm -rf it to start over (with overlay, after `umount` of any layer a killed build left mounted).
# Build-time mount points stay behind in the image as empty entries (/etc/pip.conf, /opt/pypi, ...):
# buildah 1.28 does not remove them; a docker build has none.
# Inspect the result with the same storage flags, e.g.:
#   buildah --root "$SHIMMY_BUILD_WORK/storage-overlay" --runroot "$SHIMMY_BUILD_WORK/run-overlay" \
#       --storage-driver overlay images
set -euo pipefail

repo="$(cd "$(dirname "$0")/.." && pwd)"
work="${SHIMMY_BUILD_WORK:-/var/tmp/shimmy-image-build}"
image="${SHIMMY_IMAGE:-localhost/shimmy:local}"
suite=bookworm
base_names=("docker.io/library/python:3.11-slim-bookworm" "localhost/python:3.11-slim-bookworm")
rootfs="$work/rootfs-$suite"
stamp_file="$rootfs/.shimmy-base-stamp"
# Packages for the stand-in base. passwd: useradd/groupadd (the Dockerfile creates a user).
# python3-venv brings ensurepip's pip wheel, so the venv has pip without Debian's python3-pip
# (which would be a second, unused pip for the system python).
base_packages="ca-certificates,passwd,python3,python3-venv,netbase,tzdata"
venv=/opt/venv
base_path="$venv/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"

# buildah's storage driver: overlay where the kernel mounts one on the work folder's file system (the layers
# share the unchanged files), else vfs (a full copy of the root per layer and per container: slower).
overlay_mounts() {
    local d
    d="$(mktemp -d "$work/overlay-probe.XXXXXX")" || return 1
    mkdir -p "$d/lower" "$d/upper" "$d/work" "$d/merged"
    if mount -t overlay overlay -o "lowerdir=$d/lower,upperdir=$d/upper,workdir=$d/work" "$d/merged" 2>/dev/null; then
        umount "$d/merged" || return 1
        rm -rf "$d"
        return 0
    fi
    rm -rf "$d"
    return 1
}
# chroot isolation for `buildah run` too: the OCI runtime (crun) cannot create containers
# on hosts with hybrid cgroups, and the build already relies on chroot.
export BUILDAH_ISOLATION=chroot

# ---------------------------------------------------------------- helpers
t_script=$(date +%s.%N)
declare -a timings=()
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
step() { step_name="$1"; t_step=$(now); echo; echo "=== $step_name"; }
step_done() {
    local e; e=$(elapsed "$t_step")
    timings+=("$(printf '%-62s %8ss' "$step_name" "$e")")
    echo "--- $step_name: ${e}s"
}
die() { echo; echo "BUILD BLOCKED: $*" >&2; exit 1; }

containers=()
proc_mounted=""
cleanup() {
    local rc=$?
    for c in "${containers[@]}"; do "${B[@]}" rm "$c" >/dev/null 2>&1 || true; done
    if [ -n "$proc_mounted" ]; then umount "$proc_mounted" 2>/dev/null || true; fi
    echo
    echo "=== timings"
    for t in "${timings[@]}"; do echo "$t"; done
    printf '%-62s %8ss\n' "total" "$(elapsed "$t_script")"
    [ "$rc" -eq 0 ] && echo "OK" || echo "FAILED (exit $rc)"
}
trap cleanup EXIT

[ "$(id -u)" -eq 0 ] || die "run as root (debootstrap, chroot and buildah's storage need it)"
mkdir -p "$work"
rm -rf --one-file-system "$work"/overlay-probe.*  # of a run interrupted while probing
driver="${SHIMMY_STORAGE_DRIVER:-}"
how="SHIMMY_STORAGE_DRIVER"
if [ -z "$driver" ]; then
    if overlay_mounts; then driver=overlay; else driver=vfs; fi
    how="probed: an overlay $([ "$driver" = overlay ] && echo mounts || echo does not mount) in $work"
fi
case "$driver" in overlay|vfs) ;; *) die "SHIMMY_STORAGE_DRIVER=$driver: overlay or vfs" ;; esac
B=(buildah --root "$work/storage-$driver" --runroot "$work/run-$driver" --storage-driver "$driver")
echo "buildah storage: $driver ($how), $work/storage-$driver"
# The vfs storage of this script's runs before the driver was chosen ($work/storage, with its run folder):
# deleted, not moved (its layers' records hold their paths); ~7 GB and more. Only a folder that holds
# buildah's vfs storage is removed.
if [ -d "$work/storage/vfs-layers" ] || [ -d "$work/storage/vfs-images" ]; then
    echo "removing the vfs storage of earlier runs: $work/storage"
    rm -rf --one-file-system "$work/storage"
    if [ -d "$work/run/vfs-layers" ] || [ -d "$work/run/vfs-containers" ]; then
        rm -rf --one-file-system "$work/run"
    fi
fi

# ---------------------------------------------------------------- 1. tools
step "tools (buildah, debootstrap)"
missing=()
command -v buildah >/dev/null 2>&1 || missing+=(buildah)
command -v debootstrap >/dev/null 2>&1 || missing+=(debootstrap)
if [ "${#missing[@]}" -gt 0 ]; then
    echo "installing from Debian: ${missing[*]}"
    # One apt-get at a time with the test suite's other workers (tests/conftest.py takes this lock
    # to install chromium and nginx): apt-get refuses to start while another holds apt's lock.
    exec 9>/tmp/shimmy-tests-apt.lock
    flock 9
    apt-get update -q || die "apt-get update failed: Debian's package mirror is not reachable"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}" \
        || die "apt-get install ${missing[*]} failed"
    flock -u 9
    exec 9>&-
fi
buildah --version
debootstrap --version
step_done

# ---------------------------------------------------------------- 2. mirror
step "Debian mirror (from this machine's apt sources)"
# First URI serving the suite (and its security suite) in deb822 *.sources or one-line lists.
read_mirror() {  # $1: suite to look for (bookworm or bookworm-security)
    python3 - "$1" <<'PY'
import glob, re, sys
suite = sys.argv[1]
for path in sorted(glob.glob("/etc/apt/sources.list.d/*.sources")):
    for stanza in re.split(r"\n\s*\n", open(path).read()):
        fields = {}
        for line in stanza.splitlines():
            m = re.match(r"^([A-Za-z-]+):\s*(.*)$", line)
            if m and not line.startswith("#"):
                fields[m.group(1).lower()] = m.group(2).split()
        if fields.get("enabled", ["yes"])[0] == "no" or "deb" not in fields.get("types", []):
            continue
        if suite in fields.get("suites", []) and fields.get("uris"):
            print(fields["uris"][0].rstrip("/")); sys.exit(0)
for path in ["/etc/apt/sources.list"] + sorted(glob.glob("/etc/apt/sources.list.d/*.list")):
    try:
        lines = open(path).read().splitlines()
    except OSError:
        continue
    for line in lines:
        parts = re.sub(r"\[[^]]*\]", "", line.split("#")[0]).split()
        if len(parts) >= 3 and parts[0] == "deb" and parts[2] == suite:
            print(parts[1].rstrip("/")); sys.exit(0)
sys.exit(1)
PY
}
mirror="${SHIMMY_DEBIAN_MIRROR:-$(read_mirror "$suite")}" || die "no apt source for '$suite' in /etc/apt/sources.list{,.d/*}: debootstrap needs a Debian mirror"
security_mirror="$(read_mirror "$suite-security" || true)"
echo "mirror:          $mirror"
echo "security mirror: ${security_mirror:-(none)}"
if ! curl -fsS --max-time 30 -o /dev/null "$mirror/dists/$suite/Release"; then
    die "the Debian mirror $mirror does not answer $mirror/dists/$suite/Release; debootstrap cannot fetch packages"
fi
step_done

# ---------------------------------------------------------------- 3. root filesystem
stamp="suite=$suite mirror=$mirror packages=$base_packages venv=$venv"
if [ "${SHIMMY_REBUILD_BASE:-0}" = 1 ]; then rm -rf "$rootfs"; fi
if [ -f "$stamp_file" ] && [ "$(cat "$stamp_file")" = "$stamp" ]; then
    step "debootstrap $suite root (reused: $rootfs)"
    step_done
else
    step "debootstrap $suite root"
    rm -rf "$rootfs" "$rootfs.partial"
    if ! debootstrap --variant=minbase --components=main --include="$base_packages" \
            "$suite" "$rootfs.partial" "$mirror" >"$work/debootstrap.log" 2>&1; then
        tail -n 30 "$work/debootstrap.log" >&2
        die "debootstrap $suite from $mirror failed (log: $work/debootstrap.log)"
    fi
    step_done

    step "base root: security updates, venv, cleanup"
    r="$rootfs.partial"
    {
        printf 'Types: deb\nURIs: %s\nSuites: %s %s-updates\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
            "$mirror" "$suite" "$suite"
        if [ -n "$security_mirror" ]; then
            printf '\nTypes: deb\nURIs: %s\nSuites: %s-security\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
                "$security_mirror" "$suite"
        fi
    } >"$r/etc/apt/sources.list.d/debian.sources"
    rm -f "$r/etc/apt/sources.list"
    # The host's apt settings for this one upgrade (e.g. a frozen mirror needs
    # Check-Valid-Until false); removed again afterwards, so the image keeps Debian's own.
    host_apt_conf=()
    for f in /etc/apt/apt.conf.d/*; do
        b="$(basename "$f")"
        if [ -f "$f" ] && [ ! -e "$r/etc/apt/apt.conf.d/$b" ]; then
            cp "$f" "$r/etc/apt/apt.conf.d/$b" && host_apt_conf+=("$b")
        fi
    done
    mount -t proc proc "$r/proc" && proc_mounted="$r/proc"
    chroot "$r" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive \
        sh -c 'apt-get update -q && apt-get upgrade -y -q --no-install-recommends' \
        >"$work/base-upgrade.log" 2>&1 || { tail -n 20 "$work/base-upgrade.log" >&2; die "apt-get upgrade in the $suite root failed"; }
    chroot "$r" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin /usr/bin/python3 -m venv "$venv"
    chroot "$r" "$venv/bin/python" -c 'import sys, ensurepip, venv; print("python", sys.version.split()[0], "at", sys.prefix)'
    chroot "$r" "$venv/bin/pip" --version
    umount "$r/proc" && proc_mounted=""
    for b in "${host_apt_conf[@]}"; do rm -f "$r/etc/apt/apt.conf.d/$b"; done
    # Like the slim image: no apt lists, caches or logs.
    chroot "$r" apt-get clean
    rm -rf "$r"/var/lib/apt/lists/* "$r"/var/cache/apt/*.bin "$r"/var/log/apt/* "$r"/var/log/dpkg.log \
        "$r"/tmp/* "$r"/root/.cache
    echo "$stamp" >"$r/.shimmy-base-stamp"
    mv "$r" "$rootfs"
    step_done
fi
echo "root filesystem: $(du -sh --exclude=./proc "$rootfs" 2>/dev/null | cut -f1) in $rootfs"

# ---------------------------------------------------------------- 4. base image
base_ok=""
if [ "${SHIMMY_REBUILD_BASE:-0}" != 1 ] \
    && label=$("${B[@]}" inspect --type image --format '{{index .OCIv1.Config.Labels "org.shimmy.base-stamp"}}' "${base_names[0]}" 2>/dev/null) \
    && [ "$label" = "$stamp" ]; then
    base_ok=1
fi
if [ -n "$base_ok" ]; then
    step "base image ${base_names[0]} (reused)"
    step_done
else
    step "base image ${base_names[0]} from the root filesystem"
    for n in "${base_names[@]}"; do "${B[@]}" rmi -f "$n" >/dev/null 2>&1 || true; done
    ctr=$("${B[@]}" from scratch)
    containers+=("$ctr")
    mnt=$("${B[@]}" mount "$ctr")
    tar -C "$rootfs" --numeric-owner --xattrs --exclude=./.shimmy-base-stamp \
        --exclude='./proc/*' --exclude='./sys/*' --exclude='./dev/*' --exclude='./run/*' -cf - . \
        | tar -C "$mnt" --numeric-owner --xattrs -xpf -
    "${B[@]}" umount "$ctr" >/dev/null
    "${B[@]}" config --os linux --arch "$(dpkg --print-architecture)" \
        --env "PATH=$base_path" --env LANG=C.UTF-8 --env "VIRTUAL_ENV=$venv" \
        --cmd python3 --label "org.shimmy.base-stamp=$stamp" \
        --label "org.shimmy.note=debootstrap $suite + Debian python3 in $venv; stand-in for python:3.11-slim-bookworm" \
        "$ctr"
    "${B[@]}" commit --quiet --format docker "$ctr" "${base_names[0]}" >/dev/null
    for n in "${base_names[@]:1}"; do "${B[@]}" tag "${base_names[0]}" "$n"; done
    "${B[@]}" rm "$ctr" >/dev/null
    containers=()
    step_done
fi
"${B[@]}" images --filter reference='*python*'

# ---------------------------------------------------------------- 5. build
step "buildah build (Dockerfile unchanged)"
# The host's effective pip configuration (files + PIP_* variables) as one pip.conf.
pipconf="$work/pip.conf"
python3 -m pip config list 2>/dev/null | python3 -c '
import re, sys
sections = {}
for line in sys.stdin:
    m = re.match(r"^([^.=]*)\.([^=]+)=(.*)$", line.strip())
    if not m:
        continue
    section, key, value = m.groups()
    value = value.strip().strip("\x27\"")
    section = "global" if section in (":env:", "global") else section
    sections.setdefault(section, {})[key] = value          # later lines (env) win
for section, items in sections.items():
    print(f"[{section}]")
    for k, v in items.items():
        print(f"{k} = {v}")
' >"$pipconf"
echo "pip configuration for the build ($pipconf, mounted as /etc/pip.conf):"
sed 's/^/    /' "$pipconf"
volumes=(-v "$pipconf:/etc/pip.conf:ro")
# CA bundle(s): the system bundle and any the pip configuration names.
declare -A mounted=()
add_mount() {  # $1: host path, mounted read-only at the same path
    local p="$1"
    [ -e "$p" ] || { echo "    (not mounted, missing on the host: $p)"; return 0; }
    [ -n "${mounted[$p]:-}" ] && return 0
    mounted[$p]=1
    volumes+=(-v "$p:$p:ro")
    echo "    mount: $p"
}
add_mount /etc/ssl/certs/ca-certificates.crt
# The host's apt settings that the base lacks (e.g. a frozen mirror needs Check-Valid-Until false), for the
# Dockerfile's apt-get (it installs nginx), as for the base's upgrade above.
for f in /etc/apt/apt.conf.d/*; do
    b="$(basename "$f")"
    if [ -f "$f" ] && [ ! -e "$rootfs/etc/apt/apt.conf.d/$b" ]; then
        volumes+=(-v "$f:/etc/apt/apt.conf.d/$b:ro")
        echo "    mount: $f"
    fi
done
# Local paths named by the pip configuration: file:// indexes (the folder above .../simple,
# since index pages link to ../../files/...), find-links folders, cert and client-cert files.
while read -r p; do add_mount "$p"; done < <(
    sed -n 's/^[a-z-]* = //p' "$pipconf" | tr ' ' '\n' | sed -n 's#^file://##p; s#^\(/.*\)#\1#p' \
        | sed 's#/simple/*$##' | sort -u)

# The images of earlier builds that lost their tag to a later one (their layers are no cache for this
# build's context); an intermediate layer of a tagged image is kept (the cache of the unchanged steps).
"${B[@]}" rmi --prune >/dev/null 2>&1 || true
build_args=(build --isolation chroot --format docker --layers --pull=never
            -f "$repo/Dockerfile" -t "$image" "${volumes[@]}" "$repo")
echo "buildah ${build_args[*]}"
if ! "${B[@]}" "${build_args[@]}" 2>&1 | tee "$work/build.log"; then
    die "buildah build failed (log: $work/build.log)"
fi
step_done

size=$("${B[@]}" images --format '{{.Size}}' "$image" | head -n1)
echo "image $image: $size"
"${B[@]}" inspect --type image --format 'user={{.Docker.Config.User}} cmd={{.Docker.Config.Cmd}} healthcheck={{.Docker.Config.Healthcheck}} volumes={{.Docker.Config.Volumes}}' "$image"

if [ "${SHIMMY_SKIP_SMOKE:-0}" = 1 ]; then
    echo "smoke test skipped (SHIMMY_SKIP_SMOKE=1)"
    exit 0
fi

# ---------------------------------------------------------------- 6. smoke test
step "smoke test: imports and numba cache"
ctr=$("${B[@]}" from --pull=never "$image")
containers+=("$ctr")
"${B[@]}" run --isolation chroot "$ctr" -- python -c 'import shimmy, dash, diskcache; print("shimmy", shimmy.__version__, "dash", dash.__version__, "diskcache", diskcache.__version__)'
"${B[@]}" run --isolation chroot "$ctr" -- python -c '
import os, time
t = time.perf_counter()
import shimmy
r = shimmy.simulate("nes_pd", 30, 150e3, t_end=1)
d = os.environ["NUMBA_CACHE_DIR"]
n = sum(len(f) for _, _, f in os.walk(d))
print(f"uid {os.getuid()}, cwd {os.getcwd()}: first simulate in a fresh process {time.perf_counter() - t:.2f} s "
      f"(success={r.success}); {n} numba cache files in {d}; shimmy from {shimmy.__file__}")
raise SystemExit(0 if n and r.success else "numba cache in the image is empty (or simulate failed)")'
step_done

# A free loopback port on the host (chroot isolation shares the host's network).
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
if "${B[@]}" run --isolation chroot "$ctr" -- test -f app.py; then
    step "smoke test: the image's CMD (nginx in front of gunicorn) + GET /api/v1/health, then SIGTERM"
    cat >"$work/smoke_http.py" <<'PY'
"""Start the image's CMD on a loopback port instead of 0.0.0.0:8050 (nginx in front of gunicorn), GET the
health URL and a page through nginx, stop it with SIGTERM as `docker stop` does: both must end, status 0."""
import json, signal, subprocess, sys, time, urllib.request

port = sys.argv[1]
cmd = ["python", "-m", "shimmy", "serve", "--listen", f"127.0.0.1:{port}", "--workers", "2", "--run-dir", "/run/shimmy"]
print("starting:", " ".join(cmd), flush=True)
t0 = time.perf_counter()
proc = subprocess.Popen(cmd)
ok = False
try:
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/v1/health", timeout=5) as resp:
                body = resp.read().decode()
                print(f"GET /api/v1/health -> {resp.status} (Server: {resp.headers['Server']}) after "
                      f"{time.perf_counter() - t0:.1f} s: {body[:500]}")
                ok = resp.status == 200 and resp.headers["Server"] == "nginx"
                break
        except OSError:
            time.sleep(0.5)
    if proc.poll() is not None:
        print(f"shimmy serve exited with {proc.returncode} before answering", flush=True)
    elif ok:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=30) as resp:
            print(f"GET / -> {resp.status}, {len(resp.read())} bytes")
finally:
    if proc.poll() is None:
        t1 = time.perf_counter()
        proc.send_signal(signal.SIGTERM)
        try:
            code = proc.wait(45)
            print(f"SIGTERM: shimmy serve (nginx and gunicorn) exited {code} after {time.perf_counter() - t1:.1f} s")
            ok = ok and code == 0
        except subprocess.TimeoutExpired:
            proc.kill()
            ok = False
sys.exit(0 if ok else 1)
PY
    "${B[@]}" run --isolation chroot -v "$work/smoke_http.py:/tmp/smoke_http.py:ro" "$ctr" -- python /tmp/smoke_http.py "$port" \
        || die "the image's nginx and gunicorn did not answer /api/v1/health or stop cleanly (see output above)"
    step_done
else
    echo
    echo "NOTE: the image has no app.py: smoke test checked the imports only (no server/health check)."
fi

if "${B[@]}" run --isolation chroot "$ctr" -- python -c 'import distributed' 2>/dev/null; then
    step "smoke test: dask scheduler + worker run shimmy.simulate"
    cat >"$work/smoke_dask.py" <<'PY'
"""Scheduler and one worker as compose.yaml starts them (loopback ports), one task."""
import subprocess, sys, time, urllib.request

port, http_port = sys.argv[1], sys.argv[2]
addr = f"tcp://127.0.0.1:{port}"
procs = [subprocess.Popen(["dask", "scheduler", "--host", "127.0.0.1", "--port", port,
                           "--dashboard-address", f"127.0.0.1:{http_port}"])]
ok = False
try:
    for _ in range(120):
        try:
            urllib.request.urlopen(f"http://127.0.0.1:{http_port}/health", timeout=2).read()
            print("scheduler /health answered", flush=True)
            break
        except OSError:
            time.sleep(0.5)
    procs.append(subprocess.Popen(["dask", "worker", addr, "--nworkers", "1", "--nthreads", "1",
                                   "--host", "127.0.0.1", "--dashboard-address", "127.0.0.1:0"]))
    from distributed import Client
    import shimmy
    with Client(addr, timeout=60) as client:
        client.wait_for_workers(1, timeout=60)
        r = client.submit(shimmy.simulate, "nes_pd", 30, 150e3, t_end=1).result(timeout=120)
        print(f"dask worker ran shimmy.simulate: success={r.success}, {r.t.size} samples, {r.response_type}")
        ok = bool(r.success)
finally:  # the worker first, then the scheduler (a worker told at once with its scheduler hangs
    for p in reversed(procs):  # 8 s on the closing connection before its nanny kills it)
        p.terminate()
        try:
            p.wait(30)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait(10)
sys.exit(0 if ok else 1)
PY
    dport=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
    hport=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
    "${B[@]}" run --isolation chroot -v "$work/smoke_dask.py:/tmp/smoke_dask.py:ro" "$ctr" -- python /tmp/smoke_dask.py "$dport" "$hport" \
        || die "dask smoke test failed (see output above)"
    step_done
fi

echo
echo "image: $image ($size), built from $repo/Dockerfile on a debootstrap $suite base"
