"""Where a slider step's time goes on the Overview (the fast-start issue's slider -> figure figure).

    python benchmarks/bench_slider.py [--repeats 8] [--port 8771] [--show 2]

Starts the service as the image runs it (nginx + gunicorn, ``bench_service.start_server``, a fresh
cache) and opens the Overview in the tests' headless Chromium. For each of ``--repeats`` r2 slider
steps (a key press) it logs inside the page: the key, every Dash request sent and answered (the
outputs it asks for, the answer's size) and every DOM change of the growth figure; prints the logs
of the last ``--show`` steps and the medians of key -> first request and key -> the figure's last
DOM change (Plotly's redraw done). The product's target for the latter: 100 ms.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "ui"), str(ROOT / "tests" / "service"),
                str(ROOT / "benchmarks")]

#: Logs, in the page: the key press, each Dash request's start, answer and body size, the figure's DOM changes.
INSTRUMENT = """
window.__log = [];
const log = (what) => window.__log.push([what, performance.now()]);
new MutationObserver(() => log('dom')).observe(document.getElementById('ov-growth'),
                                               {subtree: true, childList: true, attributes: true});
document.addEventListener('keydown', () => log('key'), true);
const f = window.fetch;
window.fetch = function(url, opts) {
  let outs = '';
  try { outs = JSON.parse(opts.body).output.slice(0, 60); } catch (e) {}
  log('request ' + outs);
  return f.apply(this, arguments).then(r => { log('answer ' + outs);
    return r.clone().text().then(t => { log('body ' + outs + ' ' + t.length + ' B'); return r; }); });
};
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=8)
    parser.add_argument("--port", type=int, default=8771)
    parser.add_argument("--show", type=int, default=2, help="the last steps whose whole log is printed")
    args = parser.parse_args()
    from bench_service import overview_slider, start_server
    from browser import chromium
    from selenium.webdriver.common.keys import Keys
    from test_browser import NES_TRACE

    cache_dir = tempfile.mkdtemp(prefix="shimmy-bench-slider-")
    os.chmod(cache_dir, 0o700)
    server = start_server(cache_dir, args.port)
    driver = chromium("chromium-bench-slider", "1500,1100")
    try:
        handle = overview_slider(driver, f"http://127.0.0.1:{args.port}")
        driver.execute_script(INSTRUMENT)
        to_request, to_figure = [], []
        for k in range(args.repeats):
            before = driver.execute_script(NES_TRACE)
            driver.execute_script("window.__log = [];")
            handle.send_keys(Keys.ARROW_RIGHT)
            # nothing asked of the page while the step is drawn (a WebDriver call every 2 ms, as this loop made
            # before, ran on the page's main thread between Dash's and Plotly's work: 111-127 ms against 98-110)
            time.sleep(1.2)
            t0 = time.perf_counter()
            while driver.execute_script(NES_TRACE) == before and time.perf_counter() - t0 < 10:
                time.sleep(0.1)
            if time.perf_counter() - t0 > 0.05:  # the change came late: its redraw may still be under way
                time.sleep(0.8)
            log = driver.execute_script("return window.__log;")
            key = next(t for what, t in log if what == "key")
            doms = [t for what, t in log if what == "dom"]
            requests = [t for what, t in log if what.startswith("request") and t >= key]
            to_figure.append(doms[-1] - key)
            to_request.append(requests[0] - key if requests else float("nan"))
            if k >= args.repeats - args.show:
                print(f"step {k + 1}:")
                for what, t in log:
                    if what != "dom":
                        print(f"  {t - key:8.1f} ms  {what}")
                print(f"  {doms[0] - key:8.1f} ms  first DOM change of the figure, {doms[-1] - key:.1f} ms the last "
                      f"({len(doms)} changes)")
        print("key -> first request (ms):", [round(v) for v in to_request],
              f"median {statistics.median(to_request):.0f}")
        print("key -> figure redrawn (ms):", [round(v) for v in to_figure], f"median {statistics.median(to_figure):.0f}")
    finally:
        driver.quit()
        server.terminate()
        server.wait(10)


if __name__ == "__main__":
    main()
