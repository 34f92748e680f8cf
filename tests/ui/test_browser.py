"""The workbench in real headless Chromium (Debian chromium + chromedriver) against gunicorn.

The test setup (tests/ui/browser.py) installs the two Debian packages when they are missing (CI
runs as root). Screenshots of every page go to screenshots/ (not committed) for a person to look at.
"""

from __future__ import annotations

import json
import re
import time
import urllib.request
from urllib.parse import parse_qs, urlparse

import pytest

selenium = pytest.importorskip("selenium")
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402

from browser import (DOWNLOADS, PAGES, SHOTS, browser_fixture, by_id, idle, job_records, on_figure,  # noqa: E402
                     open_page, pattern, severe, slider_handle, table_rows, text_of, trace_count, wait_for)

browser = browser_fixture("chromium-profile", "1500,1100", DOWNLOADS)


@pytest.mark.parametrize("name", list(PAGES))
def test_every_page_loads_without_console_errors(server, browser, name):
    browser.get_log("browser")  # drop what earlier tests left
    browser.get(server.base + PAGES[name] + "?e_p=0.002")
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, ".page-header h1"), what="the page header")
    idle(browser)
    time.sleep(1.0)
    browser.save_screenshot(str(SHOTS / f"{name}.png"))
    assert severe(browser) == []
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


def test_opening_ground_run_and_decisions_starts_no_job_and_run_computes(server, browser):
    """Pages compute nothing long on opening: the cached answer, else a Run button. Requests no
    other test asks for (a taxi with its own threshold; NES at 170 kN), so nothing is cached."""
    before = set(job_records(server))
    browser.get(server.base + "/ground-run?preset=taxi&psi_thr=0.0123")
    wait_for(lambda: "taxi preset" in text_of(browser, "gr-source"), what="the taxi preset")
    browser.get(server.base + "/design?config=nes&Fz=170")
    wait_for(lambda: "Press Compute" in text_of(browser, "sens-charts"), what="the sensitivities waiting for Compute")
    idle(browser)
    time.sleep(2.0)  # a job submitted on opening would be in the store by now
    assert set(job_records(server)) == before
    browser.get(server.base + "/ground-run?preset=taxi&psi_thr=0.0123")
    wait_for(lambda: "Press Run" in text_of(browser, "gr-plane"), what="the ground run waiting for Run")
    idle(browser)
    time.sleep(1.0)
    assert set(job_records(server)) == before
    assert browser.find_element(By.ID, "gr-run").is_enabled() and text_of(browser, "gr-status") == ""
    assert severe(browser) == []

    # Compute then computes and draws (the sensitivities: seconds; the ground run's Run: test_browser_ground_run.py).
    browser.get(server.base + "/design?config=nes&Fz=170")
    wait_for(lambda: "Press Compute" in text_of(browser, "sens-charts"), what="the sensitivities waiting for Compute")
    idle(browser)
    browser.find_element(By.ID, "sens-run").click()
    bars = wait_for(lambda: on_figure(browser, "sens-hopf_V1", "return g.data[0].y;"), timeout=120,
                    what="the tornado chart of the first Hopf speed")
    assert sorted(bars) == ["e_p (m)", "k_s (N/m)", "r2 (m)", "r3 (m)"]  # the NES's parameters
    new = [j for i, j in job_records(server).items() if i not in before]
    assert [(j["analysis"], j["request"]["config"], j["request"]["Fz"], j["status"]) for j in new] == [
        ("sensitivity", "nes", 170000.0, "done")]
    # Opened again: the cached charts at once, no job.
    browser.get(server.base + "/design?config=nes&Fz=170")
    wait_for(lambda: on_figure(browser, "sens-hopf_V1", "return g.data[0].y;"), timeout=20, what="the cached charts")
    idle(browser)
    assert len(job_records(server)) == len(before) + 1
    assert severe(browser) == []


def _active(server, ids) -> list[str]:
    """Those of ``ids`` still queued or running (the read reaps what is gone)."""
    server.request("GET", "/api/v1/jobs/none")
    records = job_records(server)
    return [i for i in ids if records.get(i, {}).get("status") in ("queued", "running")]


def test_leaving_a_page_cancels_the_jobs_it_started(server, browser):
    """Left by loading another page, or by a navigation inside the app (Back after a pushed
    address: Dash Pages replaces the page without unloading it), the page's jobs nobody else
    waits for are cancelled and give up their slots."""
    before = set(job_records(server))
    browser.get(server.base + "/ground-run?psi_thr=0.0124&r2=0.0813")  # a design of its own: its Hopf curves too
    wait_for(lambda: "take-off preset" in text_of(browser, "gr-source"), what="the take-off preset")
    idle(browser)
    browser.find_element(By.ID, "gr-run").click()
    started = wait_for(lambda: len(new := [i for i in job_records(server) if i not in before]) == 4 and new,
                       timeout=20, what="the four ground runs")
    # The page knows its jobs once its Run has been answered (a page left before that cannot name them).
    wait_for(lambda: "analyses" in text_of(browser, "gr-status"), timeout=20, what="the page reading its jobs")
    assert _active(server, started)
    browser.get(server.base + "/api")  # another page: this one unloads
    wait_for(lambda: not _active(server, started), timeout=20, what="the ground runs to be cancelled")
    assert {job_records(server)[i]["status"] for i in started} <= {"cancelled", "done"}
    assert "cancelled" in {job_records(server)[i]["status"] for i in started}

    before = set(job_records(server))
    browser.get(server.base + "/stability-map?shade=nes&fz_min=120&fz_max=480&resolution=8")
    run = wait_for(lambda: browser.find_elements(By.ID, "map-run"), what="the Compute button")[0]
    idle(browser)
    run.click()
    started = wait_for(lambda: [i for i in job_records(server) if i not in before], timeout=20, what="the map job")
    wait_for(lambda: text_of(browser, "map-status"), timeout=20, what="the page reading its job")
    assert _active(server, started)
    browser.execute_script("history.pushState(null, '', '/devices'); dispatchEvent(new PopStateEvent('popstate'));")
    wait_for(lambda: browser.find_elements(By.ID, "dev-pd"), timeout=20, what="the Devices page")
    wait_for(lambda: not _active(server, started), timeout=20, what="the map job to be cancelled")
    assert job_records(server)[started[0]]["status"] == "cancelled"
    assert job_records(server)[started[0]]["message"] == "cancelled: nobody waits for it any more"
    assert severe(browser) == []


def test_cancel_lets_the_jobs_go_and_the_page_waits_for_run_again(server, browser):
    before = set(job_records(server))
    browser.get(server.base + "/ground-run?preset=taxi&psi_thr=0.0125")
    wait_for(lambda: "taxi preset" in text_of(browser, "gr-source"), what="the taxi preset")
    idle(browser)
    browser.find_element(By.ID, "gr-run").click()
    wait_for(lambda: "Running the four configurations" in text_of(browser, "gr-plane"), timeout=20,
             what="the plane saying the runs are under way")
    started = wait_for(lambda: len(new := [i for i in job_records(server) if i not in before]) == 4 and new,
                       timeout=20, what="the four ground runs")
    wait_for(lambda: browser.find_element(By.ID, "gr-cancel").is_enabled(), timeout=20, what="Cancel enabled")
    browser.find_element(By.ID, "gr-cancel").click()
    wait_for(lambda: text_of(browser, "gr-status") == "cancelled", timeout=20, what='"cancelled"')
    assert "Press Run" in text_of(browser, "gr-plane")  # not "Running ..." for runs that were cancelled
    assert browser.find_element(By.ID, "gr-run").is_enabled()
    wait_for(lambda: not _active(server, started), timeout=20, what="the ground runs to be cancelled")
    assert severe(browser) == []


# Null until Plotly has drawn the figure (the table can render first): tests wait on it, never read it raw.
NES_TRACE = ("const g = document.querySelector('#ov-growth .js-plotly-plot');"
             "const t = g && g.data ? g.data.find(t => t.name === 'NES') : null;"
             "return t ? t.y : null;")



def _nes_onset(driver) -> str:
    """The NES onset speed in the Overview table (read in one script: no stale element references)."""
    return driver.execute_script("const r = document.querySelectorAll('#ov-hopf-table tbody tr');"
                                 "return r.length > 1 ? r[1].cells[2].innerText : '';")


def test_slider_move_updates_the_linear_stability_figure_and_the_url(server, browser):
    browser.get(server.base + "/")
    before = wait_for(lambda: _nes_onset(browser), what="the Hopf table")
    traces_before = wait_for(lambda: browser.execute_script(NES_TRACE), what="the growth-rate figure")
    handle = slider_handle(browser, "r2")
    handle.click()
    for _ in range(20):
        handle.send_keys(Keys.ARROW_RIGHT)
    after = wait_for(lambda: (v := _nes_onset(browser)) != before and v, timeout=20, what="the table to change")
    assert after != before
    traces_after = wait_for(lambda: (t := browser.execute_script(NES_TRACE)) != traces_before and t,
                            timeout=20, what="the NES growth-rate trace to change")
    assert traces_after != traces_before
    idle(browser)
    # the address is written once a design is committed and its requests are sent (arrow keys commit after
    # 0.6 s of quiet, so a loaded machine commits some steps on the way): wait for the last step's value there,
    # then for its requests. Read at an earlier commit, the table was that commit's and the reloaded address
    # the last one's (NES + PD's onset against the original's +0.798 against +0.797: r2 0.0813-0.0817 against
    # 0.0818 or more)
    box = by_id(browser, pattern("r2", "param-box"))

    def url_r2() -> float | None:
        values = parse_qs(urlparse(browser.current_url).query).get("r2")
        return float(values[0]) if values else None

    wait_for(lambda: url_r2() == float(box.get_attribute("value")), timeout=10,
             what=lambda: f"the URL to carry r2 = {box.get_attribute('value')} ({browser.current_url})")
    idle(browser)
    stepped = table_rows(browser, "#ov-hopf-table tbody tr")
    # The link reproduces the view: the whole table.
    url = browser.current_url
    browser.get(url)
    assert wait_for(lambda: _nes_onset(browser), what="the table after reload") == after
    assert table_rows(browser, "#ov-hopf-table tbody tr") == stepped
    browser.save_screenshot(str(SHOTS / "overview-after-slider.png"))
    assert severe(browser) == []


def test_background_job_shows_progress_then_its_figure(server, browser):
    browser.get(server.base + "/bifurcation?configs=original,nes&Fz=160")
    run = wait_for(lambda: browser.find_elements(By.ID, "bif-run"), what="the Compute button")[0]
    idle(browser)
    run.click()
    progress_seen = wait_for(lambda: (browser.find_element(By.ID, "bif-status").text
                                      or None), timeout=30, interval=0.05, what="a progress message")
    assert progress_seen
    assert browser.find_element(By.ID, "bif-cancel").is_enabled()
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#bif-summary tbody tr"), timeout=120,
             what="the result table")
    n_traces = wait_for(lambda: trace_count(browser, "bif-graph") > 4 and trace_count(browser, "bif-graph"),
                        what="the diagram's traces")
    assert n_traces > 4
    assert [r[0] for r in table_rows(browser, "#bif-summary tbody tr")] == ["original", "NES"]
    assert not browser.find_element(By.ID, "bif-run").get_attribute("disabled")
    browser.save_screenshot(str(SHOTS / "bifurcation-result.png"))
    assert severe(browser) == []


def test_map_click_opens_the_time_history_at_that_point(server, browser):
    browser.get(server.base + "/stability-map?shade=original&overlay=nes&fz_min=100&fz_max=400&resolution=4")
    run = wait_for(lambda: browser.find_elements(By.ID, "map-run"), what="the Compute button")[0]
    idle(browser)
    run.click()
    wait_for(lambda: browser.find_element(By.ID, "map-status").text or None, timeout=30, interval=0.05,
             what="a progress message")
    # Watched being made: the figure says what is computed and for how long, the bar never goes back
    # (two maps: one finishing first counts whole, not as nothing).
    bars, figures = [], set()
    while not browser.find_elements(By.CSS_SELECTOR, "#map-summary tbody tr"):
        assert len(bars) < 900, "the map's summary table after 180 s"
        bars.append(float(browser.find_element(By.ID, "map-progress").get_attribute("value")))
        figures.add(text_of(browser, "map-graph"))
        time.sleep(0.2)
    assert bars == sorted(bars), bars
    computing = {t for t in figures if "Computing the map (original, nes, 4 Fz slices each)" in t}
    assert len(computing) >= 2 and all("so far" in t for t in computing)  # the seconds go on
    assert not any("Press Compute" in t for t in figures)
    assert [r[0] for r in table_rows(browser, "#map-summary tbody tr")] == ["original", "NES"]
    wait_for(lambda: trace_count(browser, "map-graph") > 8, what="the map's traces")
    idle(browser)
    browser.save_screenshot(str(SHOTS / "stability-map-result.png"))
    plot = browser.find_element(By.CSS_SELECTOR, "#map-graph .nsewdrag")
    ActionChains(browser).move_to_element_with_offset(plot, -plot.size["width"] // 4, 0).click().perform()
    wait_for(lambda: "/time-history" in browser.current_url, timeout=20, what="navigation to the time history")
    url = browser.current_url
    assert "config=original" in url and "V=" in url and "Fz=" in url
    V = float(re.search(r"[?&]V=([0-9.e+-]+)", url).group(1))
    fz = float(re.search(r"[?&]Fz=([0-9.e+-]+)", url).group(1))
    assert 1 <= V <= 200 and 100 <= fz <= 400
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#th-metrics .metric"), timeout=60,
             what="the time history at the clicked point")
    assert float(browser.find_element(By.ID, "th-v").get_attribute("value")) == pytest.approx(V, rel=1e-5)
    assert severe(browser) == []


def test_study_page_runs_a_study_and_tabulates_it(server, browser):
    browser.get(server.base + "/study?parameter=e_p&values=0.0005,0.005&configs=nes,nes_pd")
    run = wait_for(lambda: browser.find_elements(By.ID, "study-run"), what="the Compute button")[0]
    idle(browser)
    run.click()
    rows = wait_for(lambda: table_rows(browser, "#study-summary tbody tr"), timeout=120,
                    what="the study table")
    assert len(rows) == 4
    first = rows[0]
    assert first[0] == "0.0005" and first[1] == "NES" and float(first[2]) > 6
    # per configuration: three exact curves over the whole range (Hopf start, end, min shimmy load), the
    # largest stable |psi| on its grid of diagrams (lines and markers), the two sampled values as markers
    # on the four panels but the third (and each configuration's largest stable |psi| marked; special
    # points and legend keys aside)
    wait_for(lambda: trace_count(browser, "study-graph") >= 12, what="four panels x two configurations")
    modes = browser.execute_script("return document.querySelector('#study-graph .js-plotly-plot').data"
                                   ".filter(t => t.x[0] !== null && !(t.meta && (t.meta.kind || t.meta.mark)))"
                                   ".map(t => t.mode + ':' + (t.x.length > 2 ? 'range' : 'samples'));")
    assert sorted(modes) == sorted(["lines:range"] * 6 + ["lines+markers:range"] * 2 + ["markers:samples"] * 6)
    marks = browser.execute_script("return document.querySelector('#study-graph .js-plotly-plot').data"
                                   ".filter(t => t.meta && t.meta.mark).map(t => t.meta.config);")
    assert sorted(marks) == ["nes", "nes_pd"]
    browser.save_screenshot(str(SHOTS / "study-result.png"))
    assert severe(browser) == []


def test_time_history_operating_point_button(server, browser):
    browser.get(server.base + "/time-history")
    idle(browser)
    wait_for(lambda: browser.find_elements(By.ID, "th-run"), what="the Run button")[0].click()
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#th-metrics .metric"), timeout=60,
             what="the first run")
    first = browser.find_element(By.ID, "th-metrics").text
    button = next(b for b in browser.find_elements(By.CSS_SELECTOR, ".op-buttons button") if b.text.startswith("D"))
    button.click()
    wait_for(lambda: browser.find_element(By.ID, "th-metrics").text not in ("", first), timeout=60,
             what="the run at point D")
    def titles():
        return [t.text for t in browser.find_elements(By.CSS_SELECTOR, "#th-series .gtitle")]

    wait_for(lambda: any("Fz = 350 kN" in t for t in titles()), timeout=20, what="the figure title at point D")
    wait_for(lambda: "Fz=350" in browser.current_url, timeout=10, what="the URL to carry the point")
    assert severe(browser) == []


def test_results_download_as_csv_and_json(server, browser):
    for f in DOWNLOADS.glob("*"):
        f.unlink()
    browser.get(server.base + "/")
    wait_for(lambda: _nes_onset(browser), what="the Hopf table")
    wait_for(lambda: browser.find_element(By.ID, "ov-csv").is_enabled(), what="the download button")
    browser.find_element(By.ID, "ov-csv").click()
    browser.find_element(By.ID, "ov-json").click()
    expected = ["overview_hopf.csv", "overview_stability.json"]
    wait_for(lambda: all((DOWNLOADS / name).exists() for name in expected), timeout=20, what="two downloads")
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
    run = wait_for(lambda: browser.find_elements(By.ID, "th-run"), what="the Run button")[0]
    idle(browser)
    browser.set_network_conditions(offline=False, latency=0, download_throughput=100 * 1024,
                                   upload_throughput=1024 * 1024)  # bytes/s: the result takes seconds
    try:
        run.click()
        wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#th-metrics .metric"), timeout=120,
                 what="the result over the slow link")
        slowest = browser.execute_script("return Math.max(...performance.getEntriesByType('resource')"
                                         ".filter(e => e.name.includes('_dash-update')).map(e => e.duration));")
        assert slowest > 1000  # ms: the drawn answer did take longer than several poll intervals
    finally:
        browser.delete_network_conditions()
    assert trace_count(browser, "th-series") > 0
    assert severe(browser) == []


def _gate_outputs(server, store: str) -> int:
    """How many outputs the page's check of answers landing through ``store`` writes (Dash's callback map)."""
    with urllib.request.urlopen(server.base + "/_dash-dependencies", timeout=30) as answer:
        callbacks = json.load(answer)
    gate = next(c for c in callbacks if any(i["id"] == store for i in c["inputs"]))
    return gate["output"].count("...") + 1 if gate["output"].startswith("..") else 1


def test_an_answer_landing_after_a_later_action_of_the_page_is_dropped(server, browser):
    """A draw of jobs the page has let go that lands after the later action's answer (a speed typed back to
    one computed before: its cached answer drawn at once) would replace the newer answer with the older one.
    The page applies an answer of its reads only if its store still names the jobs' watcher when it lands."""
    open_page(browser, server, "/time-history?config=original&V=47&Fz=190")
    n = _gate_outputs(server, "th-drawn")
    assert n > 10  # the page's outputs and its job state
    browser.execute_script("window.dash_clientside.set_props('th-go', {data: {jobs: [], requests: [],"
                           " watcher: 'the-later-action'}});")

    def land(watcher, k, value):
        browser.execute_script("window.dash_clientside.set_props('th-drawn', {data: arguments[0]});",
                               {"watcher": watcher, "n": n, "set": [[k, value]], "id": f"{watcher}-{k}"})

    land("an-earlier-action", n - 1, "the older answer")  # the status line (the last of the page's state)
    land("the-later-action", n - 2, "42")  # the progress bar's value, of the jobs the page waits for
    wait_for(lambda: browser.find_element(By.ID, "th-progress").get_attribute("value") == "42", timeout=30,
             what="the answer of the jobs the page waits for")
    assert text_of(browser, "th-status") != "the older answer"
    land("the-later-action", n - 1, "the newer answer")
    wait_for(lambda: text_of(browser, "th-status") == "the newer answer", timeout=30, what="the status line")
    assert severe(browser) == []
