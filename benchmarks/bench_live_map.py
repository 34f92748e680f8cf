"""The map following the design in the workbench (the live-maps issue's workbench figures).

    python benchmarks/bench_live_map.py [--config nes] [--steps 3]

Starts gunicorn (app:server, 2 workers, a fresh cache directory) on loopback and opens the
Stability map page in headless Chromium at 1440x900 with the default plane (V 1-200 m/s, Fz
10-900 kN, 10 slices). Prints, from the page as a user sees it (the figure's title read every
50 ms):

* the cold map: Compute click -> the first curves drawn (the Hopf curves), -> the map shaded;
* then ``--steps`` design steps of e_p (+2 %, about a slider step), each typed into the design
  panel: value entered -> the previous map faint, -> the first curves of the new design drawn,
  -> the new map shaded; with the warm map's own time (``elapsed_s``) and what it carried.

A step's time includes the job's queueing and start, its computation, the page's poll and the
drawing (a typed value is followed at once: no settle delay, which only the arrow keys have).
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "ui"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_service import start_server  # noqa: E402
from browser import by_id, chromium, idle, on_figure, pattern, type_into, wait_for  # noqa: E402


def title(driver) -> str:
    return on_figure(driver, "map-graph", "return (g.layout.title && g.layout.title.text) || '';") or ""


def faded(driver) -> bool:
    return bool(on_figure(driver, "map-graph", "return (g.layout.shapes || []).some(s => s.xref === 'paper' "
                                               "&& s.fillcolor && s.fillcolor.indexOf('255,255,255') >= 0);"))


def watch(driver, t0: float, marks: dict[str, callable], timeout: float = 600.0) -> dict[str, float]:
    """Seconds from t0 until each mark's condition holds, checked in turn (each after the one before
    it, every 50 ms), until the last or the timeout."""
    seen: dict[str, float] = {}
    for name, holds in marks.items():
        while not holds():
            if time.perf_counter() - t0 > timeout:
                return seen
            time.sleep(0.05)
        seen[name] = time.perf_counter() - t0
    return seen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="nes")
    parser.add_argument("--steps", type=int, default=3)
    parser.add_argument("--port", type=int, default=8768)
    args = parser.parse_args()
    cache_dir = tempfile.mkdtemp(prefix="shimmy-bench-live-")
    os.chmod(cache_dir, 0o700)
    server = start_server(cache_dir, args.port)
    driver = chromium("bench-live-map", "1440,900")
    base = f"http://127.0.0.1:{args.port}"
    e_p = 0.001
    try:
        driver.get(f"{base}/stability-map?shade={args.config}")
        run = wait_for(lambda: driver.find_elements("id", "map-run"), what="the Compute button")[0]
        idle(driver)
        t0 = time.perf_counter()
        run.click()
        cold = watch(driver, t0, {"curves": lambda: title(driver).startswith("Making the map"),
                                  "shaded": lambda: title(driver).startswith("Shimmy type of")})
        print(f"cold map ({args.config}): first curves {cold.get('curves', math.nan):.1f} s, "
              f"shaded {cold.get('shaded', math.nan):.1f} s after the click")
        rows = []
        for k in range(args.steps):
            e_p = round(e_p * 1.02, 8)
            box = by_id(driver, pattern("e_p", "param-box"))
            t0 = time.perf_counter()
            type_into(box, f"{e_p:g}")
            step = watch(driver, t0, {
                "faint": lambda: faded(driver) or "new design" in title(driver).lower(),
                "curves": lambda: title(driver).startswith("Making the new design's map"),
                "shaded": lambda: title(driver).startswith("Shimmy type of") and not faded(driver)})
            rows.append(step)
            print(f"step {k + 1} (e_p {e_p:g} m): faint {step.get('faint', math.nan):.1f} s, first curves "
                  f"{step.get('curves', math.nan):.1f} s, shaded {step.get('shaded', math.nan):.1f} s "
                  "after the value was entered")
        for key in ("faint", "curves", "shaded"):
            values = [r[key] for r in rows if key in r]
            if values:
                print(f"median over {len(values)} steps, {key}: {statistics.median(values):.1f} s")
    finally:
        driver.quit()
        server.terminate()
        server.wait(10)


if __name__ == "__main__":
    main()
