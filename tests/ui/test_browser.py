"""The workbench in real headless Chromium (Debian chromium + chromedriver) against gunicorn.

The test setup installs the two Debian packages when they are missing (CI runs as root).
Screenshots of every page go to screenshots/ (not committed) for a person to look at.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import time
from pathlib import Path

import pytest

selenium = pytest.importorskip("selenium")
from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SHOTS = ROOT / "screenshots"
DOWNLOADS = ROOT / ".pytest_cache" / "downloads"
CHROMIUM, CHROMEDRIVER = "/usr/bin/chromium", "/usr/bin/chromedriver"
PAGES = {"overview": "/", "devices": "/devices", "time-history": "/time-history", "bifurcation": "/bifurcation",
         "stability-map": "/stability-map", "study": "/study", "design": "/design", "validation": "/validation",
         "api": "/api"}


def _ensure_chromium() -> None:
    if os.path.exists(CHROMIUM) and os.path.exists(CHROMEDRIVER):
        return
    if os.geteuid() != 0 or not shutil.which("apt-get"):
        pytest.fail("Debian chromium and chromium-driver are needed and cannot be installed here (not root)")
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    subprocess.run(["apt-get", "update", "-qq"], check=True, env=env)
    subprocess.run(["apt-get", "install", "-y", "-qq", "chromium", "chromium-driver"], check=True, env=env)


def chromium(profile: str, window: str, downloads: Path | None = None):
    """Headless Chromium on a profile of its own (``profile`` under .pytest_cache), started once
    for a module: a second browser on the same profile, started while the first is still closing,
    would hand its pages to that one."""
    _ensure_chromium()
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--disable-dev-shm-usage", f"--window-size={window}"):
        opts.add_argument(arg)
    opts.add_argument(f"--user-data-dir={ROOT / '.pytest_cache' / profile}")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    if downloads is not None:
        downloads.mkdir(parents=True, exist_ok=True)
        opts.add_experimental_option("prefs", {"download.default_directory": str(downloads),
                                               "download.prompt_for_download": False})
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    driver.set_page_load_timeout(60)
    SHOTS.mkdir(exist_ok=True)
    return driver


@pytest.fixture(scope="module")
def browser():
    driver = chromium("chromium-profile", "1500,1100", DOWNLOADS)
    yield driver
    driver.quit()


def _severe(driver) -> list[str]:
    return [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]


def _wait_for(predicate, timeout=60.0, interval=0.1, what="condition"):
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(interval)
    raise AssertionError(f"timed out waiting for {what}")


def _idle(driver, timeout=60.0):
    """Dash has no callback in flight (the renderer sets data-dash-is-loading on busy components)."""
    _wait_for(lambda: not driver.find_elements(By.CSS_SELECTOR, "[data-dash-is-loading='true']"), timeout,
              what="Dash to be idle")


@pytest.mark.parametrize("name", list(PAGES))
def test_every_page_loads_without_console_errors(server, browser, name):
    browser.get_log("browser")  # drop what earlier tests left
    browser.get(server.base + PAGES[name] + "?e_p=0.002")
    _wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, ".page-header h1"), what="the page header")
    _idle(browser)
    time.sleep(1.0)
    browser.save_screenshot(str(SHOTS / f"{name}.png"))
    assert _severe(browser) == []
    # Works offline: every resource the page loaded came from our own server (no CDN).
    origins = browser.execute_script("return performance.getEntriesByType('resource').map(e => e.name);")
    assert origins and all(u.startswith(server.base) for u in origins), [u for u in origins
                                                                         if not u.startswith(server.base)]
    # The design panel is on every page that uses the design, and took the design from the URL; the
    # pages that ignore it (validation, API) keep it hidden.
    panel = browser.find_element(By.ID, "design-panel")
    if name in ("validation", "api"):
        assert not panel.is_displayed()
    else:
        assert "Design" in panel.text


# Null until Plotly has drawn the figure (the table can render first): tests wait on it, never read it raw.
NES_TRACE = ("const g = document.querySelector('#ov-growth .js-plotly-plot');"
             "const t = g && g.data ? g.data.find(t => t.name === 'NES') : null;"
             "return t ? t.y : null;")


def _trace_count(driver, graph_id: str) -> int:
    """Traces Plotly has drawn in a dcc.Graph (0 until it has drawn: the figure can lag the tables)."""
    return driver.execute_script(f"const g = document.querySelector('#{graph_id} .js-plotly-plot');"
                                 "return g && g.data ? g.data.length : 0;")


def _nes_onset(driver) -> str:
    """The NES onset speed in the Overview table (read in one script: no stale element references)."""
    return driver.execute_script("const r = document.querySelectorAll('#ov-hopf-table tbody tr');"
                                 "return r.length > 1 ? r[1].cells[2].innerText : '';")


def test_slider_move_updates_the_linear_stability_figure_and_the_url(server, browser):
    browser.get(server.base + "/")
    before = _wait_for(lambda: _nes_onset(browser), what="the Hopf table")
    traces_before = _wait_for(lambda: browser.execute_script(NES_TRACE), what="the growth-rate figure")
    handle = browser.find_elements(By.CSS_SELECTOR, "[role='slider']")[0]  # r2
    handle.click()
    for _ in range(20):
        handle.send_keys(Keys.ARROW_RIGHT)
    after = _wait_for(lambda: (v := _nes_onset(browser)) != before and v, timeout=20, what="the table to change")
    assert after != before
    traces_after = _wait_for(lambda: (t := browser.execute_script(NES_TRACE)) != traces_before and t,
                             timeout=20, what="the NES growth-rate trace to change")
    assert traces_after != traces_before
    _wait_for(lambda: "r2=" in browser.current_url, timeout=10, what="the URL to carry r2")
    # The link reproduces the view.
    url = browser.current_url
    browser.get(url)
    assert _wait_for(lambda: _nes_onset(browser), what="the table after reload") == after
    browser.save_screenshot(str(SHOTS / "overview-after-slider.png"))
    assert _severe(browser) == []


def test_background_job_shows_progress_then_its_figure(server, browser):
    browser.get(server.base + "/bifurcation?configs=original,nes&Fz=160")
    run = _wait_for(lambda: browser.find_elements(By.ID, "bif-run"), what="the Compute button")[0]
    _idle(browser)
    run.click()
    progress_seen = _wait_for(lambda: (browser.find_element(By.ID, "bif-status").text
                                       or None), timeout=30, interval=0.05, what="a progress message")
    assert progress_seen
    assert browser.find_element(By.ID, "bif-cancel").is_enabled()
    _wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#bif-summary tbody tr"), timeout=120,
              what="the result table")
    n_traces = _wait_for(lambda: _trace_count(browser, "bif-graph") > 4 and _trace_count(browser, "bif-graph"),
                         what="the diagram's traces")
    assert n_traces > 4
    rows = browser.find_elements(By.CSS_SELECTOR, "#bif-summary tbody tr")
    assert [r.find_elements(By.TAG_NAME, "td")[0].text for r in rows] == ["original", "NES"]
    assert not browser.find_element(By.ID, "bif-run").get_attribute("disabled")
    browser.save_screenshot(str(SHOTS / "bifurcation-result.png"))
    assert _severe(browser) == []


def test_map_click_opens_the_time_history_at_that_point(server, browser):
    browser.get(server.base + "/stability-map?shade=original&overlay=nes&fz_min=100&fz_max=400&resolution=4")
    run = _wait_for(lambda: browser.find_elements(By.ID, "map-run"), what="the Compute button")[0]
    _idle(browser)
    run.click()
    _wait_for(lambda: browser.find_element(By.ID, "map-status").text or None, timeout=30, interval=0.05,
              what="a progress message")
    rows = _wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#map-summary tbody tr"), timeout=180,
                     what="the map's summary table")
    assert [r.find_elements(By.TAG_NAME, "td")[0].text for r in rows] == ["original", "NES"]
    _wait_for(lambda: _trace_count(browser, "map-graph") > 8, what="the map's traces")
    _idle(browser)
    browser.save_screenshot(str(SHOTS / "stability-map-result.png"))
    plot = browser.find_element(By.CSS_SELECTOR, "#map-graph .nsewdrag")
    ActionChains(browser).move_to_element_with_offset(plot, -plot.size["width"] // 4, 0).click().perform()
    _wait_for(lambda: "/time-history" in browser.current_url, timeout=20, what="navigation to the time history")
    url = browser.current_url
    assert "config=original" in url and "V=" in url and "Fz=" in url
    V = float(re.search(r"[?&]V=([0-9.e+-]+)", url).group(1))
    fz = float(re.search(r"[?&]Fz=([0-9.e+-]+)", url).group(1))
    assert 1 <= V <= 200 and 100 <= fz <= 400
    _wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#th-metrics .metric"), timeout=60,
              what="the time history at the clicked point")
    assert float(browser.find_element(By.ID, "th-v").get_attribute("value")) == pytest.approx(V, rel=1e-5)
    assert _severe(browser) == []


def test_study_page_runs_a_study_and_tabulates_it(server, browser):
    browser.get(server.base + "/study?parameter=e_p&values=0.0005,0.005&configs=nes,nes_pd")
    run = _wait_for(lambda: browser.find_elements(By.ID, "study-run"), what="the Compute button")[0]
    _idle(browser)
    run.click()
    rows = _wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#study-summary tbody tr"), timeout=120,
                     what="the study table")
    assert len(rows) == 4
    first = rows[0].find_elements(By.TAG_NAME, "td")
    assert first[0].text == "0.0005" and first[1].text == "NES" and float(first[2].text) > 6
    assert _wait_for(lambda: _trace_count(browser, "study-graph") == 6, what="three panels x two configurations")
    browser.save_screenshot(str(SHOTS / "study-result.png"))
    assert _severe(browser) == []


def test_time_history_operating_point_button(server, browser):
    browser.get(server.base + "/time-history")
    _idle(browser)
    _wait_for(lambda: browser.find_elements(By.ID, "th-run"), what="the Run button")[0].click()
    _wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#th-metrics .metric"), timeout=60,
              what="the first run")
    first = browser.find_element(By.ID, "th-metrics").text
    button = next(b for b in browser.find_elements(By.CSS_SELECTOR, ".op-buttons button") if b.text.startswith("D"))
    button.click()
    _wait_for(lambda: browser.find_element(By.ID, "th-metrics").text not in ("", first), timeout=60,
              what="the run at point D")
    def titles():
        return [t.text for t in browser.find_elements(By.CSS_SELECTOR, "#th-series .gtitle")]

    _wait_for(lambda: any("Fz = 350 kN" in t for t in titles()), timeout=20, what="the figure title at point D")
    _wait_for(lambda: "Fz=350" in browser.current_url, timeout=10, what="the URL to carry the point")
    assert _severe(browser) == []


def test_results_download_as_csv_and_json(server, browser):
    for f in DOWNLOADS.glob("*"):
        f.unlink()
    browser.get(server.base + "/")
    _wait_for(lambda: _nes_onset(browser), what="the Hopf table")
    _wait_for(lambda: browser.find_element(By.ID, "ov-csv").is_enabled(), what="the download button")
    browser.find_element(By.ID, "ov-csv").click()
    browser.find_element(By.ID, "ov-json").click()
    expected = ["overview_hopf.csv", "overview_stability.json"]
    _wait_for(lambda: all((DOWNLOADS / name).exists() for name in expected), timeout=20, what="two downloads")
    files = sorted(p.name for p in DOWNLOADS.glob("overview_*") if not p.name.endswith(".crdownload"))
    assert files == expected
    text = (DOWNLOADS / "overview_hopf.csv").read_text()
    assert text.startswith("configuration,") and "NES + PD" in text
    import json

    data = json.loads((DOWNLOADS / "overview_stability.json").read_text())
    assert set(data["configs"]) == {"original", "nes", "pd", "nes_pd"}


def test_a_result_slower_to_arrive_than_the_poll_interval_is_still_drawn(server, browser):
    """A job's result that takes seconds to reach the page (a slow link here; a loaded machine or a
    long run elsewhere) is drawn: Dash drops the answer of a callback whose input changed while it
    was on its way, so a result drawn by the 400 ms poll itself never arrived (plotly/dash#1613)."""
    browser.get(server.base + "/time-history?config=pd&V=61.3&Fz=187&t_end=10")  # a run no other test asks for
    run = _wait_for(lambda: browser.find_elements(By.ID, "th-run"), what="the Run button")[0]
    _idle(browser)
    browser.set_network_conditions(offline=False, latency=0, download_throughput=100 * 1024,
                                   upload_throughput=1024 * 1024)  # bytes/s: the result takes seconds
    try:
        run.click()
        _wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#th-metrics .metric"), timeout=120,
                  what="the result over the slow link")
        slowest = browser.execute_script("return Math.max(...performance.getEntriesByType('resource')"
                                         ".filter(e => e.name.includes('_dash-update')).map(e => e.duration));")
        assert slowest > 1000  # ms: the drawn answer did take longer than several poll intervals
    finally:
        browser.delete_network_conditions()
    assert _trace_count(browser, "th-series") > 0
    assert _severe(browser) == []
