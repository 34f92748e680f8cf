"""Disturbance margins in the workbench, in real Chromium against gunicorn (tests/ui/browser.py): on the Time
history page at original (50 m/s, 550 kN), opened as from a Bistable map point, the margins' table names the
torsional cycle with its smallest yaw kick (~0.0165 rad) and its Run button runs the time history from just above
it, which ends torsional; on the map page the margins of a small plane are drawn over the map, as markers under
labelled contour lines. Bounded: one point, a 2 x 2 plane; waits, no timing assertions."""

from __future__ import annotations

import re
import time

import pytest

selenium = pytest.importorskip("selenium")
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402

from browser import (SHOTS, browser_fixture, by_id, idle, on_figure, open_page, severe, table_rows,  # noqa: E402
                     text_of, trace_count, type_into, wait_for)

browser = browser_fixture("chromium-margins", "1440,900")
POINT = "/time-history?config=original&V=50&Fz=550&map_type=Bistable"
#: 2 x 2 cells centred on V 60 and 100 m/s, Fz 600 and 800 kN (three bistable), over a map of 3 slices.
PLANE = ("/stability-map?shade=original&v_min=40&v_max=120&fz_min=500&fz_max=900&resolution=3&margin_nv=2"
         "&margin_nfz=2")


#: A figure's title (none on a placeholder figure, while a run is made).
TITLE = "return (g.layout.title && g.layout.title.text) || '';"
#: a title with its subtitle, if any
HEADING = ("const t = g.layout.title || {}; "
           "return (t.text || '') + ' | ' + ((t.subtitle && t.subtitle.text) || '');")


def _small(browser) -> None:
    """The window at 1024 x 768, once the page fits it (the figures redrawn to the width)."""
    browser.set_window_size(1024, 768)
    wait_for(lambda: browser.execute_script("return document.documentElement.scrollWidth <= "
                                            "document.documentElement.clientWidth"), timeout=10,
             what="the page to fit 1024 px")
    idle(browser)


def _rows(browser) -> list[list[str]]:
    return table_rows(browser, "#thm-summary tbody tr")


def test_margins_of_a_bistable_point_and_a_run_from_the_torsional_threshold(server, browser):
    open_page(browser, server, POINT, clear_log=True)
    assert "Bistable" in text_of(browser, "th-bistable") and "disturbance margins" in text_of(browser, "th-bistable")
    browser.find_element(By.ID, "thm-run").click()
    wait_for(lambda: _rows(browser), timeout=240, what=lambda: "the margins' table (status: "
             + text_of(browser, "thm-status") + text_of(browser, "thm-error") + ")")
    rows = _rows(browser)
    torsional = next(r for r in rows if r[0].startswith("torsional limit cycle"))
    lateral = next(r for r in rows if r[0].startswith("lateral limit cycle"))
    assert "standard start ends here" in lateral[0] and lateral[3].startswith("0 ")
    kick = float(re.match(r"([0-9.]+) ±", torsional[3]).group(1))
    assert 0.0155 < kick < 0.0175
    assert torsional[4].startswith("yes") and "→ lateral" in torsional[4] and "→ torsional" in torsional[4]
    assert float(torsional[1]) == pytest.approx(0.187, rel=0.02)
    idle(browser)
    browser.execute_script("document.getElementById('thm-summary').scrollIntoView({block: 'center'})")
    browser.save_screenshot(str(SHOTS / "time-history-margins-1440.png"))
    k = rows.index(torsional)
    button = by_id(browser, '{"index":%d,"type":"thm-run"}' % k)
    start = float(re.search(r"psi0 = ([0-9.]+) rad", button.text).group(1))
    assert kick < start < kick * 1.01  # just above the threshold
    button.click()
    wait_for(lambda: "torsional limit cycle" in text_of(browser, "th-settled"), timeout=240,
             what=lambda: "the run from the kick to end torsional (" + text_of(browser, "th-settled")
             + text_of(browser, "th-status") + ")")
    settled = text_of(browser, "th-settled")
    assert f"psi0 = {start:g} rad" in settled and "settled on" in settled
    assert float(browser.find_element(By.ID, "th-psi0").get_attribute("value")) == start
    assert float(browser.find_element(By.ID, "th-tend").get_attribute("value")) >= 80
    wait_for(lambda: browser.execute_script("return window.scrollY < 5;"), timeout=10,
             what="the page scrolled up to the run")
    idle(browser)
    browser.save_screenshot(str(SHOTS / "time-history-kick-1440.png"))
    _small(browser)
    browser.execute_script("document.getElementById('thm-summary').scrollIntoView({block: 'center'})")
    browser.save_screenshot(str(SHOTS / "time-history-margins-1024.png"))
    browser.set_window_size(1440, 900)
    # another point: the map's note goes, the margins shown say they are of the previous point
    browser.set_window_size(1440, 900)
    browser.execute_script("window.scrollTo(0, 0)")
    type_into(browser.find_element(By.ID, "th-v"), "51")
    wait_for(lambda: not text_of(browser, "th-bistable"), timeout=30, what="the map's note to go")
    wait_for(lambda: "previous one" in text_of(browser, "thm-status"), timeout=30, what="the margins' stale status")
    # a row's Run of the margins shown (of 50 m/s): the boxes go back to their point, and it runs there
    rows = _rows(browser)
    k = next(i for i, r in enumerate(rows) if r[0].startswith("torsional limit cycle"))
    button = by_id(browser, '{"index":%d,"type":"thm-run"}' % k)
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'})", button)
    button.click()
    wait_for(lambda: browser.find_element(By.ID, "th-v").get_attribute("value") == "50", timeout=30,
             what="the speed back at the margins' point")
    wait_for(lambda: "V = 50 m/s," in (on_figure(browser, "th-series", TITLE) or "")
             and "torsional limit cycle" in text_of(browser, "th-settled")
             and f"psi0 = {start:g} rad" in text_of(browser, "th-settled"), timeout=240,
             what=lambda: "the run from the kick at the margins' point (figure: "
             + repr(on_figure(browser, "th-series", TITLE)) + "; settled: " + text_of(browser, "th-settled")
             + "; status: " + text_of(browser, "th-status") + ")")
    assert severe(browser) == []


def test_margins_on_the_map_over_its_regions_and_a_click_runs_from_the_kick(server, browser):
    open_page(browser, server, PLANE, clear_log=True)
    browser.find_element(By.ID, "map-run").click()
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#map-summary tbody tr"), timeout=300,
             what="the map")
    browser.find_element(By.ID, "mapm-run").click()
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#mapm-summary tbody tr"), timeout=300,
             what=lambda: "the margins' table (status: " + text_of(browser, "mapm-status") + ")")
    wait_for(lambda: trace_count(browser, "mapm-graph") > 3, timeout=30, what="the margins figure")
    kicks = on_figure(browser, "mapm-graph", "const t = g.data.filter(t => t.name === 'min yaw kick')[0];"
                                             "return [t.x, t.y, t.marker.color];")
    assert list(zip(kicks[0], kicks[1], strict=True)) == [(60, 600), (100, 600), (60, 800)]
    assert all(0 < v < 0.4 for v in kicks[2])
    hover = on_figure(browser, "mapm-graph", "return g.data.filter(t => t.name === 'min yaw kick')[0].customdata[0];")
    assert hover.startswith("min yaw kick to torsional shimmy: ") and hover.endswith(")")
    # over the markers, contour lines of the cells' margins on their grid (none at (100, 800): not multistable),
    # drawn as line paths clipped to the three cells, each level labelled
    x, y, z, contours = on_figure(browser, "mapm-graph", "const t = g.data.filter(t => t.name === 'iso-margin "
                                                         "lines')[0]; return [t.x, t.y, t.z, t.contours];")
    margin = dict(zip(zip(kicks[0], kicks[1], strict=True), kicks[2], strict=True))
    assert (x, y) == ([60, 100], [600, 800]) and contours["coloring"] == "lines"
    assert z == [[margin[60, 600], margin[100, 600]], [margin[60, 800], None]]
    levels = round((contours["end"] - contours["start"]) / contours["size"]) + 1
    assert 4 <= levels <= 8 and min(kicks[2]) < contours["start"] < contours["end"] < max(kicks[2])
    drawn = browser.execute_script("return [...document.querySelectorAll('#mapm-graph g.contourlevel path')]"
                                   ".filter(p => (p.getAttribute('d') || '').length > 10).length;")
    assert drawn >= levels  # the line of each level, over its halo
    assert browser.execute_script("return document.querySelectorAll('#mapm-graph clipPath.contourclip').length;") > 0
    labels = browser.execute_script("return [...document.querySelectorAll('#mapm-graph .annotation-text')]"
                                    ".map(e => e.textContent);")
    assert [float(t) for t in labels if re.fullmatch(r"0\.\d+", t)] == pytest.approx(
        [contours["start"] + k * contours["size"] for k in range(levels)])
    # over the map: its regions (filled) and curves drawn under the margins
    assert on_figure(browser, "mapm-graph", "return g.data.filter(t => t.fill === 'toself').length;") > 0
    heading = on_figure(browser, "mapm-graph", HEADING)
    assert "smallest yaw kick to torsional shimmy | from straight rolling, in the " in heading
    assert heading.endswith(" cells where it coexists with another attractor")
    assert "compute the map above" not in heading
    assert [r[0] for r in table_rows(browser, "#mapm-summary tbody tr")] == ["600", "800"]
    assert not browser.find_element(By.ID, "mapm-csv").get_attribute("disabled")
    idle(browser)
    browser.execute_script("document.getElementById('mapm-graph').scrollIntoView()")
    browser.save_screenshot(str(SHOTS / "stability-map-margins-1440.png"))
    _small(browser)
    browser.execute_script("document.getElementById('mapm-graph').scrollIntoView()")
    browser.save_screenshot(str(SHOTS / "stability-map-margins-1024.png"))
    # opened again: the map and its margins from the cache at once, nothing computed
    open_page(browser, server, PLANE)
    wait_for(lambda: on_figure(browser, "mapm-graph", "return g.data.some(t => t.name === 'min yaw kick');"),
             timeout=30, what="the margins from the cache")
    assert browser.find_element(By.ID, "mapm-progress").get_attribute("value") in ("0", "100")
    # a click on the cell at (60 m/s, 600 kN), its marker a quarter in from the left and the bottom: its time
    # history from just above its kick
    plot = browser.find_element(By.CSS_SELECTOR, "#mapm-graph .nsewdrag")
    ActionChains(browser).move_to_element_with_offset(plot, -plot.size["width"] // 4,
                                                      plot.size["height"] // 4).click().perform()
    wait_for(lambda: "/time-history" in browser.current_url, timeout=30, what="navigation to the time history")
    url = browser.current_url
    assert "V=60" in url and "Fz=600" in url and "psi0=" in url and "map_type=Bistable" in url
    wait_for(lambda: "torsional limit cycle" in text_of(browser, "th-settled"), timeout=240,
             what="the run from the cell's kick to end torsional")
    assert "Bistable" in text_of(browser, "th-bistable")
    assert severe(browser) == []


def test_a_bistable_map_point_runs_every_start_and_the_series_shows_the_last_cycles(server, browser):
    """Opened from a Bistable map point with run=1: the standard start and the two large starts are run and
    tabulated with the attractor each ends on (lateral from the standard start, torsional from a large
    yaw); the series figure opens on the last cycles, every sample as a line there and the whole run as
    a band, and the line follows a zoom from the cached result."""
    open_page(browser, server, POINT + "&run=1", clear_log=True)
    wait_for(lambda: len(browser.find_elements(By.CSS_SELECTOR, "#th-starts tbody tr")) == 3, timeout=300,
             what=lambda: "the three starts (" + text_of(browser, "th-status") + text_of(browser, "th-error") + ")")
    rows = table_rows(browser, "#th-starts tbody tr")
    assert rows[0][0].startswith("psi0 = 0.001 rad") and "lateral limit cycle" in rows[0][1]
    assert rows[1][0].startswith("psi0 = 0.2 rad") and "torsional limit cycle" in rows[1][1]
    assert float(rows[1][2]) == pytest.approx(0.187, rel=0.03)
    idle(browser)
    shape = on_figure(browser, "th-series", "return [g.layout.xaxis.range, g.data.length, g.data[2].x.length, "
                                            "g.data[1].fill, (g.layout.xaxis3 || {}).rangeslider.visible, "
                                            "g.data[2].x[0], g.data[2].x[g.data[2].x.length - 1]];")
    (t0, t1), traces, samples, fill, slider, first, last = shape
    assert traces == 9 and fill == "tonexty" and slider is True  # three rows: band top, band, line
    assert 55 < t0 < t1 == pytest.approx(60) and t1 - t0 < 1.5  # the last 8 cycles at ~12 Hz
    assert samples <= 800 and first <= t0 + 0.01 and last >= t1 - 0.01  # every sample of the window
    browser.execute_script("Plotly.relayout(document.querySelector('#th-series .js-plotly-plot'), "
                           "{'xaxis.range': [10, 11]});")
    wait_for(lambda: on_figure(browser, "th-series", "return g.data[2].x[0];") is not None
             and 9.9 < on_figure(browser, "th-series", "return g.data[2].x[0];") <= 10.0, timeout=20,
             what="the line to follow the zoom")
    browser.execute_script("Plotly.relayout(document.querySelector('#th-series .js-plotly-plot'), "
                           "{'xaxis.autorange': true});")
    wait_for(lambda: on_figure(browser, "th-series", "return g.layout.annotations[0].visible;") is True, timeout=20,
             what="the note that the whole run is too long for a line")
    assert on_figure(browser, "th-series", "return g.data[2].x.length;") == 0
    browser.execute_script("Plotly.relayout(document.querySelector('#th-series .js-plotly-plot'), "
                           "{'xaxis.range': [52, 60]});")
    wait_for(lambda: on_figure(browser, "th-series", "return g.layout.annotations[0].visible;") is False, timeout=20,
             what="the line back for 8 s")
    idle(browser)
    time.sleep(0.5)  # the redraw has landed: the view stays where the user put it
    assert on_figure(browser, "th-series", "return g.layout.xaxis.range;") == pytest.approx([52, 60], abs=1e-6)
    browser.execute_script("document.getElementById('th-series').scrollIntoView({block: 'start'})")
    idle(browser)
    browser.save_screenshot(str(SHOTS / "time-history-series-1440.png"))
    browser.execute_script("window.scrollTo(0, 0)")
    browser.save_screenshot(str(SHOTS / "time-history-bistable-starts-1440.png"))
    _small(browser)
    browser.save_screenshot(str(SHOTS / "time-history-bistable-starts-1024.png"))
    browser.set_window_size(1440, 900)
    assert severe(browser) == []
