"""The Design decisions page in real headless Chromium against gunicorn (the Chromium starter of
test_browser.py, a profile of its own): tornado charts, a small robustness run, a small optimiser run and
the link that opens its optimum in the workbench."""

from __future__ import annotations

import time

import pytest

pytest.importorskip("selenium")
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402

from test_browser import SHOTS, _idle, _severe, _trace_count, _wait_for, chromium  # noqa: E402


@pytest.fixture(scope="module")
def browser():
    driver = chromium("chromium-profile-design", "1440,900")
    yield driver
    driver.quit()


def _text(driver, element_id: str) -> str:
    return driver.execute_script("const e = document.getElementById(arguments[0]); return e ? e.innerText : '';",
                                 element_id)


def _plot(driver, graph_id: str, script: str):
    """``script`` on the drawn figure ``g`` of a dcc.Graph (null until Plotly has drawn it)."""
    return driver.execute_script(f"const g = document.querySelector('#{graph_id} .js-plotly-plot');"
                                 f"if (!g || !g.data) {{ return null; }} {script}")


def _type(element, text: str) -> None:
    element.click()
    element.send_keys(Keys.CONTROL, "a")
    element.send_keys(Keys.BACKSPACE)
    element.send_keys(text)
    element.send_keys(Keys.TAB)


def _open(driver, server, path):
    driver.get_log("browser")
    driver.get(server.base + path)
    _wait_for(lambda: driver.find_elements(By.CSS_SELECTOR, ".page-header h1"), what="the page header")


def test_tornado_charts_for_nes_at_150_kN(server, browser):
    _open(browser, server, "/design?config=nes&Fz=150")
    bars = _wait_for(lambda: _plot(browser, "sens-hopf_V1", "return g.data[0].y;"), timeout=120,
                     what="the tornado chart of the first Hopf speed")
    assert sorted(bars) == ["e_p (m)", "k_s (N/m)", "r2 (m)", "r3 (m)"]  # the NES's parameters, with units
    half = _plot(browser, "sens-hopf_V1", "return g.data[0].x;")
    assert bars[-1] == "e_p (m)" and abs(half[-1]) == max(map(abs, half))  # the largest effect on top
    title = _plot(browser, "sens-hopf_V1", "return g.layout.xaxis.title.text;")
    assert title == "change of V1 (m/s) per half its design range"
    for key in ("hopf_V2", "hopf_interval", "min_shimmy_Fz", "max_psi"):
        assert _trace_count(browser, f"sens-{key}") == 1, key
    assert "(kN)" in _plot(browser, "sens-min_shimmy_Fz", "return g.layout.xaxis.title.text;")
    assert "a_p, rho_p: not fitted in this configuration" in _text(browser, "sens-charts")
    browser.find_elements(By.CSS_SELECTOR, "#sens-by input")[1].click()  # per +1 % of the value
    _wait_for(lambda: _plot(browser, "sens-hopf_V1", "return g.data[0].x;") not in (None, half), timeout=10,
              what="bars per 1 %")
    browser.find_elements(By.CSS_SELECTOR, "#sens-show input")[1].click()  # all parameters
    _wait_for(lambda: len(_plot(browser, "sens-hopf_V1", "return g.data[0].y;") or []) > 15, timeout=10,
              what="the gear's parameters too")
    _wait_for(lambda: "bars=per_percent" in browser.current_url and "show=all" in browser.current_url, timeout=10,
              what="the address to carry the view")
    _idle(browser)
    browser.save_screenshot(str(SHOTS / "design-tornado.png"))
    # Another design: the charts say they answer the old one until Compute is pressed.
    _type(browser.execute_script("return document.getElementById('{\"name\":\"r2\",\"type\":\"param-box\"}')"),
          "0.085")
    _wait_for(lambda: "the design changed" in _text(browser, "sens-stale"), timeout=10, what="the stale notice")
    browser.find_element(By.ID, "sens-run").click()
    _wait_for(lambda: _text(browser, "sens-stale") == "", timeout=60, what="the charts of the new design")
    # A load out of range is refused at the field, in kN, and the old charts go.
    _type(browser.find_element(By.ID, "des-fz"), "5")
    _wait_for(lambda: _text(browser, "des-fz-error"), timeout=10, what="the refusal at the load")
    assert _text(browser, "des-fz-error") == "Fz = 5 kN is outside [10, 900] kN"
    _wait_for(lambda: not browser.find_elements(By.ID, "sens-hopf_V1"), timeout=10, what="the charts to go")
    assert _severe(browser) == []


def test_a_small_robustness_run_shows_histograms_statistics_and_shimmy_probabilities(server, browser):
    _open(browser, server, "/design?config=nes&samples=16&tols=k_lam%3D0.05,k_s%3D0.05:uniform")
    _idle(browser)
    samples = browser.find_element(By.ID, "rob-samples")
    _type(samples, "1")
    _wait_for(lambda: _text(browser, "rob-samples-error"), timeout=10, what="the refusal at the samples")
    assert _text(browser, "rob-samples-error") == "samples = 1 is outside [2, 2048]"
    browser.find_element(By.ID, "rob-run").click()
    _wait_for(lambda: _text(browser, "rob-error"), timeout=10, what="the refused run")
    assert _text(browser, "rob-status") == ""  # nothing was submitted
    _type(samples, "16")
    _wait_for(lambda: _text(browser, "rob-samples-error") == "", timeout=10, what="the refusal to clear")
    browser.find_element(By.ID, "rob-run").click()
    rows = _wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#rob-stats tbody tr"), timeout=120,
                     what="the statistics table")
    assert [r.find_elements(By.TAG_NAME, "td")[0].text for r in rows] == [
        "Hopf speed 1 at 150 kN (m/s)", "Hopf speed 2 at 150 kN (m/s)", "Minimum shimmy load (kN)"]
    for graph in ("rob-hist-V1", "rob-hist-V2", "rob-hist-Fzmin"):
        kinds = _wait_for(lambda g=graph: _plot(browser, g, "return g.data.map(t => t.type);"), timeout=20,
                          what=f"the histogram {graph}")
        assert kinds == ["histogram", "scatter"], graph  # the samples and the linear-propagation density
    points = _wait_for(lambda: _plot(browser, "rob-shimmy", "return g.data.map(t => t.x.length);"), timeout=20,
                       what="the probabilities of shimmy")
    assert points == [9, 9]  # sampled and linear, at A-I
    assert "16 samples (seed 0) of k_lam 5 % normal, k_s 5 % uniform" in _text(browser, "rob-warnings")
    _idle(browser)
    browser.find_element(By.ID, "rob-histograms").location_once_scrolled_into_view  # noqa: B018
    time.sleep(0.5)
    browser.save_screenshot(str(SHOTS / "design-robustness.png"))
    assert _severe(browser) == []


@pytest.mark.slow
def test_a_small_optimiser_run_shows_the_optimum_and_opens_it_in_the_workbench(server, browser):
    # opt_seed=3: not the request tests/service/test_api.py computes on the same server (a cached answer is shown at
    # once, with no progress to see)
    _open(browser, server, "/design?config=nes&search=e_p&starts=2&runs=1&opt_seed=3&k_s=1300000"
                           "&cons=max_psi%3C%3D0.5")
    _idle(browser)
    browser.find_element(By.ID, "opt-run").click()
    _wait_for(lambda: _text(browser, "opt-status"), timeout=30, interval=0.05, what="the optimiser's progress")
    link = _wait_for(lambda: browser.find_elements(By.ID, "opt-link"), timeout=180, what="the optimum")[0]
    cells = browser.execute_script("return [...document.querySelectorAll('#opt-design-table tbody tr')]"
                                   ".map(r => [...r.cells].map(c => c.innerText));")
    assert len(cells) == 1 and cells[0][0] == "e_p"
    optimum = float(cells[0][4])
    figures = _text(browser, "opt-figures-table")
    assert "minimum shimmy load (kN)" in figures and "largest stable torsional amplitude at 150 kN (rad)" in figures
    assert "evaluations (gradient)" in _text(browser, "opt-result-line")
    history = _wait_for(lambda: _plot(browser, "opt-history", "return g.data.map(t => t.name);"), timeout=20,
                        what="the convergence history")
    assert "best feasible so far" in history and any(n.startswith("feasible") for n in history)
    _idle(browser)
    browser.find_element(By.ID, "opt-history").location_once_scrolled_into_view  # noqa: B018
    time.sleep(0.5)
    browser.save_screenshot(str(SHOTS / "design-optimiser.png"))
    href = link.get_attribute("href")
    assert "config=nes" in href and "e_p=" in href and "k_s=1300000" in href  # the whole design
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", link)  # not under the sticky bar
    link.click()
    _wait_for(lambda: "/design" not in browser.current_url, timeout=20, what="the workbench")
    box = _wait_for(lambda: browser.execute_script(
        "return document.getElementById('{\"name\":\"e_p\",\"type\":\"param-box\"}')"), what="the e_p box")
    assert float(box.get_attribute("value")) == pytest.approx(optimum, rel=1e-5)
    k_s = browser.execute_script("return document.getElementById('{\"name\":\"k_s\",\"type\":\"param-box\"}')")
    assert float(k_s.get_attribute("value")) == 1300000
    assert _severe(browser) == []
