"""Service benchmarks: cached API latency, sustained cached throughput, slider-to-figure latency.

    python benchmarks/bench_service.py [--seconds 5] [--repeats 5]

Starts gunicorn (app:server, 2 workers, a fresh cache directory) on loopback, then:

* cached API answer: median and 95th percentile of POST /api/v1/hopf (a cache hit) over 300
  sequential requests on one keep-alive connection (target median <= 20 ms);
* sustained throughput: cached requests per second from 8 client threads for --seconds
  (target >= 200/s with 2 workers); the uncached baseline (distinct requests) in the same run;
* slider move to updated linear-stability figure in headless Chromium: a key press on the r2
  slider until the Overview figure is redrawn with the new data, timed inside the page
  (keydown event to the figure's last DOM change; the driver-polled time is printed too),
  median of --repeats moves
  (target <= 300 ms).
"""

from __future__ import annotations

import argparse
import http.client
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def start_server(cache_dir: str, port: int) -> subprocess.Popen:
    env = {**os.environ, "SHIMMY_CACHE_DIR": cache_dir}
    proc = subprocess.Popen([sys.executable, "-m", "gunicorn", "app:server", "--bind", f"127.0.0.1:{port}",
                             "--workers", "2", "--no-control-socket", "--log-level", "warning"], cwd=ROOT, env=env)
    for _ in range(200):
        try:
            urllib.request.urlopen(f"http://127.0.0.1:{port}/api/v1/health", timeout=1)
            return proc
        except OSError:
            time.sleep(0.2)
    proc.kill()
    raise RuntimeError("gunicorn did not start")


def post(conn: http.client.HTTPConnection, path: str, body: dict) -> tuple[int, bytes]:
    conn.request("POST", path, json.dumps(body), {"Content-Type": "application/json"})
    resp = conn.getresponse()
    return resp.status, resp.read()


def throughput(port: int, bodies, seconds: float, threads: int = 8) -> float:
    count = [0] * threads
    stop = time.time() + seconds

    def worker(k):
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        i = k
        while time.time() < stop:
            status, _ = post(conn, "/api/v1/hopf", bodies[i % len(bodies)])
            assert status == 200
            count[k] += 1
            i += threads

    ts = [threading.Thread(target=worker, args=(k,)) for k in range(threads)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    return sum(count) / seconds


def slider_latency(base: str, repeats: int) -> list[float]:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from test_browser import NES_TRACE, _ensure_chromium, _nes_onset  # the tests' own setup

    _ensure_chromium()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--disable-dev-shm-usage", "--window-size=1500,1100"):
        opts.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)
    try:
        driver.get(base + "/")
        deadline = time.time() + 60
        while not _nes_onset(driver) and time.time() < deadline:
            time.sleep(0.05)
        handle = driver.find_elements(By.CSS_SELECTOR, "[role='slider']")[0]
        handle.click()
        time.sleep(1.0)
        # In-page clock: keydown -> the last DOM change of the figure (Plotly's redraw done).
        driver.execute_script(
            "window.__marks = []; new MutationObserver(() => window.__marks.push(performance.now()))"
            ".observe(document.getElementById('ov-growth'), {subtree: true, childList: true, attributes: true});"
            "document.addEventListener('keydown', () => { window.__key = performance.now(); }, true);")
        in_page, outside = [], []
        for _ in range(repeats):
            before = driver.execute_script(NES_TRACE)
            driver.execute_script("window.__marks = [];")
            t0 = time.perf_counter()
            handle.send_keys(Keys.ARROW_RIGHT)
            while driver.execute_script(NES_TRACE) == before and time.perf_counter() - t0 < 10:
                time.sleep(0.002)
            outside.append(time.perf_counter() - t0)
            time.sleep(0.6)  # let the redraw finish
            in_page.append(driver.execute_script("return (window.__marks[window.__marks.length - 1] - window.__key)"
                                                 " / 1000;"))
        return in_page, outside
    finally:
        driver.quit()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    port = 8765
    with tempfile.TemporaryDirectory() as cache_dir:
        proc = start_server(cache_dir, port)
        try:
            conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
            body = {"config": "nes", "Fz": 150000, "v_max": 200}
            post(conn, "/api/v1/hopf", body)  # fill the cache
            lat = []
            for _ in range(300):
                t0 = time.perf_counter()
                status, _ = post(conn, "/api/v1/hopf", body)
                lat.append(time.perf_counter() - t0)
                assert status == 200
            lat.sort()
            cached = [{"config": c, "Fz": 150000.0 + k, "v_max": 200} for c in ("original", "nes") for k in range(5)]
            for b in cached:
                post(conn, "/api/v1/hopf", b)
            rate = throughput(port, cached, args.seconds)
            fresh = [{"config": c, "Fz": 200000.0 + k, "v_max": 200} for c in ("original", "nes", "pd", "nes_pd")
                     for k in range(10_000)]
            fresh_rate = throughput(port, fresh, min(args.seconds, 3.0))
            moves, polled = slider_latency(f"http://127.0.0.1:{port}", args.repeats)
        finally:
            proc.terminate()
            proc.wait(timeout=20)
    print(f"{'measure':<52}{'value':>12}{'target':>12}")
    print(f"{'cached POST /hopf median (ms)':<52}{1e3 * statistics.median(lat):>12.2f}{'<= 20':>12}")
    print(f"{'cached POST /hopf 95th percentile (ms)':<52}{1e3 * lat[int(0.95 * len(lat))]:>12.2f}{'':>12}")
    print(f"{'cached requests/s, 2 workers, 8 client threads':<52}{rate:>12.0f}{'>= 200':>12}")
    print(f"{'uncached requests/s (baseline, same run)':<52}{fresh_rate:>12.0f}{'':>12}")
    print(f"{'cached / uncached throughput':<52}{rate / fresh_rate:>11.1f}x{'':>12}")
    print(f"{'slider key -> figure redrawn, in page, median of %d (ms)' % len(moves):<52}"
          f"{1e3 * statistics.median(moves):>12.0f}{'<= 300':>12}")
    print(f"{'slider key -> figure redrawn, in page, max (ms)':<52}{1e3 * max(moves):>12.0f}{'':>12}")
    print(f"{'same, seen by the test driver (adds its overhead) (ms)':<52}{1e3 * statistics.median(polled):>12.0f}"
          f"{'':>12}")


if __name__ == "__main__":
    main()
