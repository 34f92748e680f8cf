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
drawing (a typed value is followed at once: no settle delay, which only the arrow keys have). It is
counted from the key that enters the value (Tab, as a slider's release: the digits are typed before),
and the marks are taken in the page (a timer every 20 ms reading the figure, its times read out
afterwards): watching from here by a WebDriver call every 50 ms took ~0.5 s of the browser's CPU per
step, from the two cores the map's workers use.
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
from browser import by_id, chromium, idle, pattern, wait_for  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402


#: The page's own watch: every 20 ms, the figure's state against the marks; each mark's time
#: (performance.now(), ms) kept in window.shimmyMarks once its condition holds (a step's after its faint).
WATCH = """
const marks = arguments[0], seen = {}, t0 = performance.now();
window.shimmyMarks = {t0: t0, seen: seen};
const state = () => {
    const g = document.querySelector('#map-graph .js-plotly-plot');
    if (!g || !g.data) { return {title: '', faded: false}; }
    const title = (g.layout.title && g.layout.title.text) || '';
    const faded = (g.layout.shapes || []).some(s => s.xref === 'paper' && s.fillcolor
                                                  && s.fillcolor.indexOf('255,255,255') >= 0);
    return {title: title, faded: faded};
};
const holds = {
    faint: s => s.faded || s.title.toLowerCase().indexOf('new design') >= 0,
    curves: s => s.title.startsWith("Making the new design's map"),
    shaded: s => s.title.startsWith('Shimmy type of') && !s.faded,
    cold_curves: s => s.title.startsWith('Making the map'),
    cold_shaded: s => s.title.startsWith('Shimmy type of'),
};
const after = {curves: 'faint', shaded: 'faint'};  // (the first curves may not be drawn: a map done first)
const timer = setInterval(() => {
    const s = state();
    for (const m of marks) {
        if (!(m in seen) && (!(m in after) || after[m] in seen) && holds[m](s)) { seen[m] = performance.now() - t0; }
    }
    if (marks[marks.length - 1] in seen || performance.now() - t0 > 600000) { clearInterval(timer); }
}, 20);
return t0;
"""


def watch(driver, marks: list[str], start, timeout: float = 600.0) -> dict[str, float]:
    """Start the page's watch of ``marks``, do ``start()`` (returns the page's time, ms, when the user's
    action happened; None: when the watch started), wait until the last mark (or the timeout); the
    seconds from that action to each mark seen."""
    t_watch = driver.execute_script(WATCH, marks)
    t_action = start()
    t_action = t_watch if t_action is None else t_action
    deadline = time.perf_counter() + timeout
    while time.perf_counter() < deadline:
        seen = driver.execute_script("return window.shimmyMarks.seen;")
        if marks[-1] in seen:
            break
        time.sleep(0.25)
    return {name: (t_watch + ms - t_action) / 1000.0 for name, ms in seen.items()}


def enter(driver, box, value: str) -> float:
    """Type ``value`` into ``box`` and enter it (Tab); the page's time (ms) just before the Tab."""
    box.click()
    box.send_keys(Keys.CONTROL, "a")
    box.send_keys(Keys.BACKSPACE)
    box.send_keys(value)
    t = driver.execute_script("return performance.now();")
    box.send_keys(Keys.TAB)
    return t


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
        cold = watch(driver, ["cold_curves", "cold_shaded"], lambda: run.click())
        print(f"cold map ({args.config}): first curves {cold.get('cold_curves', math.nan):.1f} s, "
              f"shaded {cold.get('cold_shaded', math.nan):.1f} s after the click")
        rows = []
        for k in range(args.steps):
            e_p = round(e_p * 1.02, 8)
            box = by_id(driver, pattern("e_p", "param-box"))
            step = watch(driver, ["faint", "curves", "shaded"], lambda b=box, v=f"{e_p:g}": enter(driver, b, v))
            rows.append(step)
            print(f"step {k + 1} (e_p {e_p:g} m): faint {step.get('faint', math.nan):.2f} s, first curves "
                  f"{step.get('curves', math.nan):.2f} s, shaded {step.get('shaded', math.nan):.2f} s "
                  "after the value was entered")
        for key in ("faint", "curves", "shaded"):
            values = [r[key] for r in rows if key in r]
            if values:
                print(f"median over {len(values)} steps, {key}: {statistics.median(values):.2f} s")
    finally:
        driver.quit()
        server.terminate()
        server.wait(10)


if __name__ == "__main__":
    main()
