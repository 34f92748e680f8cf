"""One unit per quantity, refusals at the field and one marker vocabulary (issue 30 items 4, 5, 6 and 10),
in real headless Chromium against gunicorn: what the pages draw and say, as the browser has it.
Screenshots of the pages at 1440x900 and 1024x768 go to screenshots/ for a person to look at."""

from __future__ import annotations

import time

import pytest

pytest.importorskip("selenium")
from selenium.webdriver.common.by import By  # noqa: E402
from browser import (SHOTS, browser_fixture, by_id, idle, on_figure, open_page, pattern, severe,  # noqa: E402
                     text_of, trace_count, type_into, wait_for)

browser = browser_fixture("chromium-profile-units", "1440,900")

SIZES = ((1440, 900), (1024, 768))
#: The vocabulary as the browser must find it (ui/markers.py).
SYMBOLS = {"H": "diamond", "GH": "star", "HH": "hexagram", "LPC": "triangle-up", "NS": "square", "PD": "x"}

#: Every tick label, axis title and text Plotly drew in a graph, and the kinds and symbols of its marked traces.
READ = """
    const sel = '.xtick text, .ytick text, .g-xtitle, .g-ytitle, .g-y2title, .g-y3title, .g-y4title, ' +
                '.g-x2title, .g-x3title, .g-x4title';
    const texts = Array.from(g.querySelectorAll(sel)).map(t => t.textContent);
    const marked = g.data.filter(t => t.meta && t.meta.kind).map(t => [t.meta.kind, (t.marker || {}).symbol]);
    return {texts: texts, marked: marked};
"""


def _read(driver, graph_id):
    return on_figure(driver, graph_id, READ)


def _shots(driver, name, graph=None):
    """The page's top and, if given, its graph at both sizes (after Plotly has redrawn for the width)."""
    for w, h in SIZES:
        driver.set_window_size(w, h)
        idle(driver)
        time.sleep(1.0)  # Plotly's resize is debounced
        driver.execute_script("window.scrollTo(0, 0);")
        driver.save_screenshot(str(SHOTS / f"units-{name}-{w}.png"))
        if graph is not None:  # the whole graph: a window tall enough for it
            element = driver.find_element(By.ID, graph)
            driver.set_window_size(w, max(h, element.size["height"] + 260))
            idle(driver)
            time.sleep(1.0)
            driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", element)
            time.sleep(0.3)
            element.screenshot(str(SHOTS / f"units-{name}-graph-{w}.png"))
    driver.set_window_size(*SIZES[0])


def _no_si_prefix(texts):
    assert not [t for t in texts if "µ" in t or t.rstrip().endswith(("m", "k", "M", "n")) and t[:1].isdigit()], texts


def test_ground_run_refuses_at_its_fields_and_shows_loads_in_kn(server, browser):
    open_page(browser, server, "/ground-run?preset=landing", clear_log=True)
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#gr-settings td[data-dash-column='unit']"),
             what="the settings table")
    units = {r[0]: r[1] for r in browser.execute_script(
        "return Array.from(document.querySelectorAll('#gr-settings tbody tr')).map(r => "
        "[r.querySelector(\"td[data-dash-column='name']\"), r.querySelector(\"td[data-dash-column='unit']\")])"
        ".filter(c => c[0]).map(c => [c[0].innerText, c[1].innerText]);")}
    assert units["Fz_static"] == units["Fz_touchdown"] == units["brake_transfer"] == "kN"
    assert "Fz (kN)" in browser.find_element(By.ID, "gr-table").text
    # the landing roll steps by the preset's 0.5 s
    times = [float(c.text) for c in browser.find_elements(By.CSS_SELECTOR, "#gr-table td[data-dash-column='t']")[:4]]
    assert times == [0.0, 0.5, 1.0, 1.5]
    # the "meaning" column is on screen, not behind a scroll bar
    overflow = browser.execute_script(
        "const t = document.querySelector('#gr-settings .dash-spreadsheet-container');"
        "const m = document.querySelector(\"#gr-settings td[data-dash-column='description']\").getBoundingClientRect();"
        "return [t.scrollWidth - t.clientWidth, m.right <= window.innerWidth];")
    assert overflow[0] <= 1 and overflow[1], overflow

    # A threshold of 5 rad is refused at its box on leaving it, before Run, in its unit, as typed.
    type_into(browser.find_element(By.ID, "gr-psi-thr"), "5")
    message = wait_for(lambda: text_of(browser, "gr-psi-thr-error"), timeout=10, what="the refusal at the box")
    assert message == "the shimmy threshold |psi| = 5 rad is outside [1e-06, 1] rad"
    # nothing was run to say it (the run's line may show a cached run's warnings, never this refusal)
    assert "threshold" not in text_of(browser, "gr-error")
    type_into(browser.find_element(By.ID, "gr-lat-thr"), "5000")
    assert "5000 mm is outside [0.0001, 1000] mm" in wait_for(lambda: text_of(browser, "gr-lat-thr-error"),
                                                              timeout=10, what="the lateral threshold's refusal")
    type_into(browser.find_element(By.ID, "gr-psi-thr"), "0.02")
    wait_for(lambda: text_of(browser, "gr-psi-thr-error") == "", timeout=10, what="the refusal to go")

    # A cell: refused at the table, by row and column, in the column's unit, as typed.
    cell = browser.find_elements(By.CSS_SELECTOR, "#gr-table td[data-dash-column='Fz']")[1]
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", cell)
    cell.click()
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.keys import Keys

    ActionChains(browser).send_keys("5000").send_keys(Keys.ENTER).perform()
    refusal = wait_for(lambda: text_of(browser, "gr-table-error"), timeout=10, what="the cell's refusal")
    assert refusal == "row 2: Fz = 5000 kN is outside [10, 900] kN"
    # and a setting in kN
    setting = next(r for r in browser.find_elements(By.CSS_SELECTOR, "#gr-settings tbody tr")
                   if r.text.startswith("Fz_static"))
    value = setting.find_element(By.CSS_SELECTOR, "td[data-dash-column='value']")
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", value)
    value.click()
    ActionChains(browser).send_keys("2000").send_keys(Keys.ENTER).perform()
    assert wait_for(lambda: text_of(browser, "gr-settings-error"), timeout=10, what="the setting's refusal") == \
        "Fz_static = 2000 kN is outside [20, 900] kN"
    _shots(browser, "ground-run", "gr-settings")
    assert severe(browser) == []


def test_overview_draws_hopf_diamonds_gh_stars_and_log_speeds_written_out(server, browser):
    open_page(browser, server, "/", clear_log=True)
    growth = wait_for(lambda: (r := _read(browser, "ov-growth")) and r["texts"] and r, what="the growth figure")
    assert {"20", "200"} <= set(growth["texts"]), growth["texts"]
    assert {kind for kind, _ in growth["marked"]} == {"H"}
    assert all(symbol == SYMBOLS[kind] for kind, symbol in growth["marked"])
    browser.find_element(By.ID, "ov-boundary-run").click()
    boundary = wait_for(lambda: (r := _read(browser, "ov-boundary-graph")) and r["marked"] and r, timeout=120,
                        what="the Hopf curves")
    kinds = {kind for kind, _ in boundary["marked"]}
    assert {"GH", "HH"} <= kinds, boundary["marked"]
    assert all(symbol == SYMBOLS[kind] for kind, symbol in boundary["marked"])
    assert "vertical load Fz (kN)" in boundary["texts"]
    _no_si_prefix(boundary["texts"] + growth["texts"])
    _shots(browser, "overview", "ov-boundary-graph")
    assert severe(browser) == []


def test_bifurcation_draws_its_points_from_the_vocabulary_and_lateral_in_mm(server, browser):
    open_page(browser, server, "/bifurcation?configs=original,nes", clear_log=True)
    browser.find_element(By.ID, "bif-run").click()
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#bif-summary tbody tr"), timeout=180,
             what="the diagram")
    info = wait_for(lambda: (r := _read(browser, "bif-graph")) and r["marked"] and r, what="the special points")
    kinds = {kind for kind, _ in info["marked"]}
    assert "H" in kinds and all(symbol == SYMBOLS[kind] for kind, symbol in info["marked"]), info["marked"]
    # at 850 kN the cycles fold: their LPC points are triangles
    open_page(browser, server, "/bifurcation?configs=original,nes&Fz=850")
    browser.find_element(By.ID, "bif-run").click()
    folds = wait_for(lambda: (r := _read(browser, "bif-graph")) and r["marked"] and r, timeout=180,
                     what="the diagram at 850 kN")
    assert "LPC" in {kind for kind, _ in folds["marked"]}
    assert all(symbol == SYMBOLS[kind] for kind, symbol in folds["marked"]), folds["marked"]
    assert "max |l_g delta| (mm)" in info["texts"]
    _no_si_prefix(info["texts"])
    largest = on_figure(browser, "bif-graph", "return g.data.filter(t => t.meta && t.meta.mark).length;")
    assert largest == 2  # the largest stable |psi| of each configuration
    _shots(browser, "bifurcation", "bif-graph")
    assert severe(browser) == []


def test_stability_map_draws_gh_stars_and_double_hopf_hexagrams_over_haloes(server, browser):
    open_page(browser, server, "/stability-map?shade=nes&resolution=4", clear_log=True)
    assert "Figures of merit" not in browser.find_element(By.TAG_NAME, "main").text  # no heading without a table
    browser.find_element(By.ID, "map-run").click()
    info = wait_for(lambda: (r := _read(browser, "map-graph")) and r["marked"]
                    and browser.find_elements(By.CSS_SELECTOR, "#map-summary tbody tr") and r, timeout=400,
                    what="the map")
    kinds = {kind for kind, _ in info["marked"]}
    assert {"GH", "HH"} <= kinds and all(symbol == SYMBOLS[kind] for kind, symbol in info["marked"])
    assert "vertical load Fz (kN)" in info["texts"]
    _no_si_prefix(info["texts"])
    haloes = on_figure(browser, "map-graph", "return g.data.filter(t => t.meta && t.meta.halo).length;")
    curves = on_figure(browser, "map-graph", "return g.data.filter(t => t.name && /: (Hopf|fold of cycles|torus)$/"
                                             ".test(t.name) && t.x[0] !== null).length;")
    assert haloes == curves > 0
    torsion = on_figure(browser, "map-graph", "return g.data.filter(t => t.name === 'Torsion' && t.fill)"
                                              ".map(t => t.fillcolor);")
    assert set(torsion) <= {"#F0E442"}
    _shots(browser, "stability-map", "map-graph")
    assert severe(browser) == []


def test_time_history_shows_lateral_displacements_in_mm(server, browser):
    open_page(browser, server, "/time-history?config=nes&V=50&Fz=350&t_end=5&lateral0=0.002", clear_log=True)
    assert browser.find_element(By.ID, "th-lat0").get_attribute("value") == "2"  # the address keeps m: 2 mm
    labels = browser.execute_script("return Array.from(document.querySelectorAll('.controls label'))"
                                    ".map(l => l.innerText);")
    assert "l_g delta0 (mm)" in labels
    type_into(browser.find_element(By.ID, "th-tend"), "0")
    assert "simulated time = 0 s is outside [0.1, 600] s" in wait_for(
        lambda: text_of(browser, "th-tend-error"), timeout=10, what="the refusal at the box")
    type_into(browser.find_element(By.ID, "th-tend"), "5")
    browser.find_element(By.ID, "th-run").click()
    info = wait_for(lambda: (r := _read(browser, "th-series")) and r["texts"] and trace_count(browser, "th-series")
                    >= 3 and r, timeout=180, what="the time history")
    assert "l_g delta (mm)" in info["texts"]
    _no_si_prefix(info["texts"])
    assert "max |l_g delta| (mm)" in browser.find_element(By.ID, "th-metrics").text
    _shots(browser, "time-history", "th-series")
    assert severe(browser) == []


def test_study_marks_the_current_design_and_the_largest_stable_amplitude(server, browser):
    open_page(browser, server, "/study?parameter=e_p&values=0.001,0.003&configs=nes", clear_log=True)
    type_into(browser.find_element(By.ID, "study-values"), "0.001, 0.003, 0.009")
    assert "value 3: e_p = 0.009 m is outside" in wait_for(lambda: text_of(browser, "study-values-error"),
                                                          timeout=10, what="the values' refusal at the box")
    type_into(browser.find_element(By.ID, "study-values"), "0.001, 0.003")
    wait_for(lambda: text_of(browser, "study-values-error") == "", timeout=10, what="the refusal to go")
    browser.find_element(By.ID, "study-run").click()
    line = "return (g.layout.shapes || []).filter(s => s.name === 'current design').map(s => s.x0);"
    assert wait_for(lambda: on_figure(browser, "study-graph", line), timeout=240, what="the study") == [0.001]
    largest = on_figure(browser, "study-graph", "return g.data.filter(t => t.meta && t.meta.mark).length;")
    assert largest == 1
    # the line follows the design panel
    type_into(by_id(browser, pattern("e_p", "param-box")), "0.002")
    wait_for(lambda: on_figure(browser, "study-graph", line) == [0.002], timeout=20, what="the line to follow e_p")
    _shots(browser, "study", "study-graph")
    assert severe(browser) == []
