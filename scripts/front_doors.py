"""Write the JSON every front door gives for a fixed set of requests, to compare before and after a
change of shape (a refactoring must leave them identical but for wall-clock times).

    python scripts/front_doors.py OUT_DIR            # one JSON file per request
    python scripts/front_doors.py OUT_DIR --api-only # the API's answers only
    python scripts/front_doors.py --compare A B      # exit 1 and list the files that differ

The command line is run as a process (``python -m shimmy ... --json``); the API's answers come
from the service's runners with a fresh, empty cache (what ``POST /api/v1/...`` returns as its
result). Keys that are wall-clock times (``elapsed_s``, ``*_seconds``, ``*_ms``) are not compared, nor
the command line's top-level ``cache`` (hit, miss or off: where the answer came from, not the answer).
"""

from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys
import tempfile

CLI = {
    "cli_params": ["params"],
    "cli_simulate": ["simulate", "--config", "nes_pd", "--V", "30", "--Fz", "150000", "--t-end", "20"],
    "cli_hopf": ["hopf", "--config", "nes", "--Fz", "150000"],
    "cli_eigen": ["eigen", "--config", "pd", "--V", "40", "--Fz", "200000"],
    "cli_bifurcation": ["bifurcation", "--config", "original", "--Fz", "150000", "--progress", "none"],
    "cli_hopf_curves": ["hopf-curves", "--config", "nes", "--progress", "none"],
    "cli_curves": ["curves", "--config", "original", "--progress", "none"],
    "cli_map": ["map", "--config", "pd", "--resolution", "8", "--progress", "none"],
    "cli_classify": ["classify", "--config", "original", "--V", "50", "--Fz", "350000"],
    "cli_metrics": ["metrics", "--configs", "original,nes", "--resolution", "6", "--progress", "none"],
    "cli_ground_run": ["ground-run", "--config", "all", "--profile", "takeoff"],
    "cli_sensitivity": ["sensitivity", "--config", "nes", "--Fz", "150000", "--no-amplitude"],
    "cli_study": ["study", "--param", "e_p", "--values", "0.001,0.004", "--configs", "nes", "--progress", "none"],
    "cli_devices": ["devices"],
}

API = {
    "api_simulate": ("simulate", {"config": "nes", "V": 50, "Fz": 350000, "t_end": 10}),
    "api_hopf": ("hopf", {"config": "pd", "Fz": 150000}),
    "api_stability": ("stability", {"Fz": 150000}),
    "api_devices": ("devices", {}),
    "api_bifurcation": ("bifurcation", {"config": "nes", "Fz": 150000}),
    "api_hopf_curves": ("hopf_curves", {"config": "original"}),
    "api_map": ("map", {"config": "original", "resolution": 8}),
    "api_study": ("study", {"parameter": "e_p", "values": [0.0005, 0.005], "configs": ["nes"]}),
    "api_ground_run": ("ground_run", {"config": "nes", "preset": "landing"}),
    "api_sensitivity": ("sensitivity", {"config": "original", "Fz": 150000}),
}

TIMES = ("elapsed_s",)


def strip_times(value):
    if isinstance(value, dict):
        return {k: strip_times(v) for k, v in value.items()
                if k not in TIMES and not k.endswith(("_seconds", "_ms"))}
    if isinstance(value, list):
        return [strip_times(v) for v in value]
    return value


def answer(value):
    """The result without the command line's note of where it came from."""
    return {k: v for k, v in value.items() if k != "cache"} if isinstance(value, dict) else value


def write(out: pathlib.Path, cli: bool = True) -> None:
    out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "SHIMMY_CACHE_DIR": tempfile.mkdtemp(prefix="front-doors-")}
    for name, args in CLI.items() if cli else ():
        done = subprocess.run([sys.executable, "-m", "shimmy", *args, "--json"], capture_output=True, text=True,
                              env=env)
        text = done.stdout if done.returncode == 0 else f"exit {done.returncode}\n{done.stderr}"
        (out / f"{name}.json").write_text(text)
        print(name, done.returncode, flush=True)
    os.environ["SHIMMY_CACHE_DIR"] = env["SHIMMY_CACHE_DIR"]
    from shimmy.service import analyses

    for name, (analysis, body) in API.items():
        result, _ = analyses.run(analysis, body)
        (out / f"{name}.json").write_text(json.dumps(result, sort_keys=True, indent=1))
        print(name, flush=True)


def compare(a: pathlib.Path, b: pathlib.Path) -> int:
    differ = []
    for path in sorted(a.glob("*.json")):
        other = b / path.name
        if not other.exists():
            differ.append(f"{path.name}: missing in {b}")
            continue
        try:
            left, right = (strip_times(answer(json.loads(p.read_text()))) for p in (path, other))
        except json.JSONDecodeError:
            left, right = path.read_text(), other.read_text()
        if json.dumps(left) != json.dumps(right):  # key order too: the command line does not sort keys
            differ.append(path.name)
    print("\n".join(differ) if differ else f"identical: {len(list(a.glob('*.json')))} files")
    return 1 if differ else 0


if __name__ == "__main__":
    if sys.argv[1:2] == ["--compare"]:
        sys.exit(compare(pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3])))
    write(pathlib.Path(sys.argv[1]), cli="--api-only" not in sys.argv[2:])
