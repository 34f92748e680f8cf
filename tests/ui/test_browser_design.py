"""The Design decisions page in real headless Chromium against gunicorn (the Chromium starter of
test_browser.py, a profile of its own): tornado charts, a small robustness run, a small optimiser run and
the link that opens its optimum in the workbench."""

from __future__ import annotations

import time

import pytest

pytest.importorskip("selenium")
from selenium.webdriver.common.by import By  # noqa: E402

from browser import (SHOTS, browser_fixture, idle, on_figure, open_page, severe, table_rows,  # noqa: E402
                     text_of, trace_count, type_into, wait_for)

browser = browser_fixture("chromium-profile-design", "1440,900")
#: How these tests open the page: the console read from there on, the window as started, no wait for idle.
AS_LOADED = {"size": None, "clear_log": True, "wait_idle": False}



def test_tornado_charts_for_nes_at_150_kN(server, browser):
    open_page(browser, server, "/design?config=nes&Fz=150", **AS_LOADED)
    run = wait_for(lambda: browser.find_elements(By.ID, "sens-run"), what="the Compute button")[0]
    idle(browser)
    run.click()  # a cached answer would be shown on opening; nothing is computed without the click
    bars = wait_for(lambda: on_figure(browser, "sens-hopf_V1", "return g.data[0].y;"), timeout=120,
                    what="the tornado chart of the first Hopf speed")
    assert sorted(bars) == ["e_p (m)", "k_s (N/m)", "r2 (m)", "r3 (m)"]  # the NES's parameters, with units
    half = on_figure(browser, "sens-hopf_V1", "return g.data[0].x;")
    assert bars[-1] == "e_p (m)" and abs(half[-1]) == max(map(abs, half))  # the largest effect on top
    title = on_figure(browser, "sens-hopf_V1", "return g.layout.xaxis.title.text;")
    assert title == "change of V1 (m/s) per half its design range"
    for key in ("hopf_V2", "hopf_interval", "min_shimmy_Fz", "max_psi"):
        assert trace_count(browser, f"sens-{key}") == 1, key
    assert "(kN)" in on_figure(browser, "sens-min_shimmy_Fz", "return g.layout.xaxis.title.text;")
    assert "a_p, rho_p: not fitted in this configuration" in text_of(browser, "sens-charts")
    browser.find_elements(By.CSS_SELECTOR, "#sens-by input")[1].click()  # per +1 % of the value
    wait_for(lambda: on_figure(browser, "sens-hopf_V1", "return g.data[0].x;") not in (None, half), timeout=10,
             what="bars per 1 %")
    browser.find_elements(By.CSS_SELECTOR, "#sens-show input")[1].click()  # all parameters
    wait_for(lambda: len(on_figure(browser, "sens-hopf_V1", "return g.data[0].y;") or []) > 15, timeout=10,
             what="the gear's parameters too")
    wait_for(lambda: "bars=per_percent" in browser.current_url and "show=all" in browser.current_url, timeout=10,
             what="the address to carry the view")
    idle(browser)
    browser.save_screenshot(str(SHOTS / "design-tornado.png"))
    # Another design: the charts say they answer the old one until Compute is pressed.
    type_into(browser.execute_script("return document.getElementById('{\"name\":\"r2\",\"type\":\"param-box\"}')"),
              "0.085")
    wait_for(lambda: "the design changed" in text_of(browser, "sens-stale"), timeout=10, what="the stale notice")
    browser.find_element(By.ID, "sens-run").click()
    wait_for(lambda: text_of(browser, "sens-stale") == "", timeout=60, what="the charts of the new design")
    # A load out of range is refused at the field, in kN, and the old charts go.
    type_into(browser.find_element(By.ID, "des-fz"), "5")
    wait_for(lambda: text_of(browser, "des-fz-error"), timeout=10, what="the refusal at the load")
    assert text_of(browser, "des-fz-error") == "Fz = 5 kN is outside [10, 900] kN"
    wait_for(lambda: not browser.find_elements(By.ID, "sens-hopf_V1"), timeout=10, what="the charts to go")
    assert severe(browser) == []


def test_a_small_robustness_run_shows_histograms_statistics_and_shimmy_probabilities(server, browser):
    open_page(browser, server, "/design?config=nes&samples=16&tols=k_lam%3D0.05,k_s%3D0.05:uniform", **AS_LOADED)
    idle(browser)
    samples = browser.find_element(By.ID, "rob-samples")
    type_into(samples, "1")
    wait_for(lambda: text_of(browser, "rob-samples-error"), timeout=10, what="the refusal at the samples")
    assert text_of(browser, "rob-samples-error") == "samples = 1 is outside [2, 2048]"
    browser.find_element(By.ID, "rob-run").click()
    wait_for(lambda: text_of(browser, "rob-error"), timeout=10, what="the refused run")
    assert text_of(browser, "rob-status") == ""  # nothing was submitted
    type_into(samples, "16")
    wait_for(lambda: text_of(browser, "rob-samples-error") == "", timeout=10, what="the refusal to clear")
    browser.find_element(By.ID, "rob-run").click()
    rows = wait_for(lambda: table_rows(browser, "#rob-stats tbody tr"), timeout=120,
                    what="the statistics table")
    assert [r[0] for r in rows] == [
        "Hopf speed 1 at 150 kN (m/s)", "Hopf speed 2 at 150 kN (m/s)", "Minimum shimmy load (kN)"]
    for graph in ("rob-hist-V1", "rob-hist-V2", "rob-hist-Fzmin"):
        kinds = wait_for(lambda g=graph: on_figure(browser, g, "return g.data.map(t => t.type);"), timeout=20,
                         what=f"the histogram {graph}")
        assert kinds == ["histogram", "scatter"], graph  # the samples and the linear-propagation density
    points = wait_for(lambda: on_figure(browser, "rob-shimmy", "return g.data.map(t => t.x.length);"), timeout=20,
                      what="the probabilities of shimmy")
    assert points == [9, 9]  # sampled and linear, at A-I
    assert "16 samples (seed 0) of k_lam 5 % normal, k_s 5 % uniform" in text_of(browser, "rob-warnings")
    idle(browser)
    browser.find_element(By.ID, "rob-histograms").location_once_scrolled_into_view  # noqa: B018
    time.sleep(0.5)
    browser.save_screenshot(str(SHOTS / "design-robustness.png"))
    assert severe(browser) == []


@pytest.mark.slow
def test_a_small_optimiser_run_shows_the_optimum_and_opens_it_in_the_workbench(server, browser):
    # opt_seed=3: not the request tests/service/test_api.py computes on the same server (a cached answer is shown at
    # once, with no progress to see)
    open_page(browser, server, "/design?config=nes&search=e_p&starts=2&runs=1&opt_seed=3&k_s=1300000"
                               "&cons=max_psi%3C%3D0.5", **AS_LOADED)
    idle(browser)
    browser.find_element(By.ID, "opt-run").click()
    wait_for(lambda: text_of(browser, "opt-status"), timeout=30, interval=0.05, what="the optimiser's progress")
    link = wait_for(lambda: browser.find_elements(By.ID, "opt-link"), timeout=180, what="the optimum")[0]
    cells = browser.execute_script("return [...document.querySelectorAll('#opt-design-table tbody tr')]"
                                   ".map(r => [...r.cells].map(c => c.innerText));")
    assert len(cells) == 1 and cells[0][0] == "e_p"
    optimum = float(cells[0][4])
    on_bound = min(abs(optimum - 0.0005), abs(optimum - 0.005)) <= 1e-3 * (0.005 - 0.0005)
    assert ("the range limits it" in cells[0][6]) == on_bound and (cells[0][6] == "inside the range") != on_bound
    assert ("the range limits the optimum" in text_of(browser, "opt-summary")) == on_bound
    figures = text_of(browser, "opt-figures-table")  # every figure of merit, for optimum, current and original
    assert "minimum shimmy load (kN)" in figures and "largest stable torsional amplitude at 150 kN (rad)" in figures
    assert "shimmy speed interval width at 150 kN" in figures and "pure-torsion area" in figures
    rows = browser.execute_script("return [...document.querySelectorAll('#opt-figures-table tbody tr')]"
                                  ".map(r => [...r.cells].map(c => c.innerText));")
    assert len(rows) == 4 and all(len(r) == 4 and "–" not in r[1:] for r in rows)
    browser.execute_script("document.getElementById('opt-summary').scrollIntoView({block: 'start'});")
    time.sleep(0.3)
    browser.save_screenshot(str(SHOTS / "design-optimiser-tables.png"))
    assert "evaluations (gradient)" in text_of(browser, "opt-result-line")
    history = wait_for(lambda: on_figure(browser, "opt-history", "return g.data.map(t => t.name);"), timeout=20,
                       what="the convergence history")
    assert "best feasible so far" in history and any(n.startswith("feasible") for n in history)
    idle(browser)
    browser.find_element(By.ID, "opt-history").location_once_scrolled_into_view  # noqa: B018
    time.sleep(0.5)
    browser.save_screenshot(str(SHOTS / "design-optimiser.png"))
    href = link.get_attribute("href")
    assert "config=nes" in href and "e_p=" in href and "k_s=1300000" in href  # the whole design
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", link)  # not under the sticky bar
    link.click()
    wait_for(lambda: "/design" not in browser.current_url, timeout=20, what="the workbench")
    box = wait_for(lambda: browser.execute_script(
        "return document.getElementById('{\"name\":\"e_p\",\"type\":\"param-box\"}')"), what="the e_p box")
    assert float(box.get_attribute("value")) == pytest.approx(optimum, rel=1e-5)
    k_s = browser.execute_script("return document.getElementById('{\"name\":\"k_s\",\"type\":\"param-box\"}')")
    assert float(k_s.get_attribute("value")) == 1300000
    assert severe(browser) == []
