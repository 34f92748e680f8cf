"""The workbench as an engineer meets it (issue 14), in real headless Chromium against gunicorn:
exact inputs, refusals in the unit of the field typed into, nothing falling back silently, one
definition of each limit, readable plots, layout at 1024 px. Screenshots of every page at 1440x900
and 1024x768 go to screenshots/ for a person to look at.
"""

from __future__ import annotations

import re
import time

import pytest

pytest.importorskip("selenium")
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402
from browser import (PAGES, SHOTS, browser_fixture, by_id, idle, open_page, pattern, severe,  # noqa: E402
                     slider_handle, text_of, trace_count, type_into, wait_for)

#: Headless Chromium as in test_browser.py, with a profile of its own.
browser = browser_fixture("chromium-profile-workbench", "1440,900")



SIZES = ((1440, 900), (1024, 768))



def test_design_box_slider_and_url_stay_in_sync(server, browser):
    open_page(browser, server, "/")
    box = wait_for(lambda: by_id(browser, pattern("r2", "param-box")), what="the r2 box")
    assert box.get_attribute("value") == "0.08"  # the value is visible before any drag
    type_into(box, "0.0853")
    wait_for(lambda: "r2=0.0853" in browser.current_url, timeout=10, what="the URL to carry the typed r2")
    slider = slider_handle(browser, "r2")
    assert float(slider.get_attribute("aria-valuenow")) == pytest.approx(0.0853)
    slider.click()
    slider.send_keys(Keys.HOME)
    wait_for(lambda: by_id(browser, pattern("r2", "param-box")).get_attribute("value") == "0.07", timeout=10,
             what="the box to follow the slider")
    wait_for(lambda: "r2=0.07" in browser.current_url, timeout=10, what="the URL to follow the slider")
    browser.get(server.base + "/?k_s=1234567")  # the URL sets the box and the slider
    idle(browser)
    k_s = wait_for(lambda: by_id(browser, pattern("k_s", "param-box")), what="the k_s box")
    assert k_s.get_attribute("value") == "1234567"
    assert severe(browser) == []


@pytest.mark.parametrize("name, start, moves, expected", [
    ("r2", "0.0853", 7, "0.0707"),  # 0.0853 -> HOME 0.07 -> 7 steps of 0.1 mm (0.0707, not 0.07070000000000001)
    ("e_p", "0.00123", 3, "0.00065"),  # 0.0005 + 3 x 0.05 mm
])
def test_slider_steps_are_engineering_steps_without_float_noise(server, browser, name, start, moves, expected):
    """A slider moves by its parameter's engineering step; the box, the tooltip, the address and the
    design sent with requests carry the value on that grid, as typed; a typed value keeps the
    precision typed."""
    open_page(browser, server, f"/?{name}={start}")
    box = wait_for(lambda: by_id(browser, pattern(name, "param-box")), what=f"the {name} box")
    assert box.get_attribute("value") == start  # typed (here: in the address) precision kept
    slider = slider_handle(browser, name)
    slider.click()
    slider.send_keys(Keys.HOME)
    for _ in range(moves):
        slider.send_keys(Keys.ARROW_RIGHT)
    wait_for(lambda: by_id(browser, pattern(name, "param-box")).get_attribute("value") == expected, timeout=10,
             what=f"the box to read {expected}")
    wait_for(lambda: f"{name}={expected}&" in browser.current_url + "&", timeout=10, what="the address to follow")
    assert float(slider.get_attribute("aria-valuenow")) == pytest.approx(float(expected), abs=1e-12)
    tips = [t.text for t in browser.find_elements(By.CSS_SELECTOR, "[id$='-tooltip']") if t.text]
    assert all(len(t) <= 8 for t in tips), tips  # no 0.07770000000000001 in a tooltip
    assert severe(browser) == []


def test_a_page_and_the_design_panel_updating_the_address_at_once_both_land(server, browser):
    """The design panel's update of the address and a page's, written in one render, both reach it
    (through one store the second overwrote the first: the address missed a slider's last step)."""
    open_page(browser, server, "/?r2=0.0853")
    browser.execute_script("const C = window.dash_clientside;"
                           "C.set_props('url-update', {data: {Fz: '123'}});"
                           "C.set_props('url-design-update', {data: {r2: '0.0811'}});")
    wait_for(lambda: "Fz=123" in browser.current_url and "r2=0.0811" in browser.current_url, timeout=10,
             what=lambda: f"both updates in the address (it reads {browser.current_url})")
    assert severe(browser) == []


def test_advanced_values_are_kept_while_their_section_is_closed(server, browser):
    """The advanced boxes are rendered when their section is first opened: until then the design keeps
    their values from the address (a slider step does not drop them), and opened they show them."""
    open_page(browser, server, "/?k_psi=400000")
    assert by_id(browser, pattern("k_psi", "param")) is None
    slider = slider_handle(browser, "r2")
    slider.click()
    slider.send_keys(Keys.ARROW_RIGHT)
    wait_for(lambda: "r2=" in browser.current_url, timeout=30, what="the step in the address")
    assert "k_psi=400000" in browser.current_url
    browser.find_element(By.CSS_SELECTOR, "#advanced summary").click()
    box = wait_for(lambda: by_id(browser, pattern("k_psi", "param")), timeout=30, what="the advanced boxes")
    assert box.get_attribute("value") == "400000"
    type_into(box, "410000")
    wait_for(lambda: "k_psi=410000" in browser.current_url, timeout=30, what="the typed value in the address")
    assert "r2=" in browser.current_url
    assert severe(browser) == []


def test_a_refused_value_keeps_the_materials_value_not_the_default_materials(server, browser):
    open_page(browser, server, "/?material=tungsten")
    type_into(by_id(browser, pattern("rho_p", "param-box")), "1")
    wait_for(lambda: text_of(browser, pattern("rho_p", "param-error")), timeout=30, what="the error at rho_p")
    assert "(kept 16500 kg/m^3)" in text_of(browser, pattern("rho_p", "param-error"))
    assert severe(browser) == []


def test_refusals_are_at_the_field_in_its_unit_quoting_what_was_typed(server, browser):
    open_page(browser, server, "/")
    assert by_id(browser, pattern("k_psi", "param")) is None  # filled when the section is first opened
    browser.find_element(By.CSS_SELECTOR, "#advanced summary").click()
    k_psi = wait_for(lambda: by_id(browser, pattern("k_psi", "param")), timeout=30, what="the advanced boxes")
    assert k_psi.get_attribute("value") == "380000"  # the design's value
    type_into(k_psi, "-5")
    wait_for(lambda: text_of(browser, pattern("k_psi", "param-error")), timeout=10, what="the error at k_psi")
    assert text_of(browser, pattern("k_psi", "param-error")).startswith(
        "k_psi = -5 N m/rad is outside [10000, 1e+07] N m/rad (kept 380000")
    # The advanced inputs are wide enough for their values.
    k_delta = by_id(browser, pattern("k_delta", "param"))
    assert browser.execute_script("return arguments[0].scrollWidth <= arguments[0].clientWidth", k_delta)
    type_into(by_id(browser, pattern("r2", "param-box")), "0.2")
    wait_for(lambda: text_of(browser, pattern("r2", "param-error")), timeout=10, what="the error at r2")
    assert text_of(browser, pattern("r2", "param-error")).startswith("r2 = 0.2 m is outside [0.07, 0.09] m")
    assert "r2=0.2" not in browser.current_url
    assert text_of(browser, "design-error") == "Not applied: r2, k_psi (see the fields)"
    browser.save_screenshot(str(SHOTS / "design-errors-at-the-field.png"))
    type_into(by_id(browser, pattern("r2", "param-box")), "0.085")  # accepted: its message goes, the other stays
    wait_for(lambda: "r2=0.085" in browser.current_url, timeout=10, what="the accepted r2 in the address")
    wait_for(lambda: text_of(browser, pattern("r2", "param-error")) == "", timeout=10, what="the r2 message gone")
    assert text_of(browser, "design-error") == "Not applied: k_psi (see the field)"
    assert text_of(browser, pattern("k_psi", "param-error")).startswith("k_psi = -5 N m/rad")

    open_page(browser, server, "/bifurcation?configs=original")
    type_into(browser.find_element(By.ID, "bif-fz"), "5")
    browser.find_element(By.ID, "bif-run").click()
    wait_for(lambda: text_of(browser, "bif-error"), timeout=10, what="the bifurcation refusal")
    assert text_of(browser, "bif-error") == "Fz = 5 kN is outside [10, 900] kN"

    open_page(browser, server, "/time-history?Fz=5000")
    assert text_of(browser, "th-error") == "The address gives Fz=5000: Fz = 5000 kN is outside [10, 900] kN."
    type_into(browser.find_element(By.ID, "th-fz"), "150")
    type_into(browser.find_element(By.ID, "th-v"), "600")
    wait_for(lambda: "V = 600" in text_of(browser, "th-error"), timeout=10, what="the V refusal")
    assert text_of(browser, "th-error") == "V = 600 m/s is outside [1, 500] m/s"
    assert severe(browser) == []


@pytest.mark.parametrize("slices, why", [("1", "Fz slices = 1 is outside [2, 80]"),
                                         ("2.5", "Fz slices = 2.5 is not a whole number"),
                                         ("1000", "Fz slices = 1000 is outside [2, 80]")])
def test_map_slices_out_of_range_are_refused_not_replaced(server, browser, slices, why):
    open_page(browser, server, "/stability-map?fz_min=100&fz_max=400")
    assert "Fz slices (2-80)" in browser.find_element(By.CSS_SELECTOR, ".controls").text  # the shared limit
    type_into(browser.find_element(By.ID, "map-res"), slices)
    browser.find_element(By.ID, "map-run").click()
    wait_for(lambda: text_of(browser, "map-error"), timeout=10, what="the refusal")
    assert text_of(browser, "map-error").startswith(why)
    assert text_of(browser, "map-status") == ""  # nothing was submitted
    # The API and the page refuse the same value by the same limit.
    status, _, body = server.request("POST", "/api/v1/jobs", {"analysis": "map", "config": "original",
                                                              "resolution": 81})
    assert status == 422 and "[2, 80]" in body["error"]


def test_nothing_falls_back_silently(server, browser):
    open_page(browser, server, "/time-history?V=abc&config=foo")
    text = text_of(browser, "th-error")
    assert "config=foo, which is not a configuration" in text and "V=abc, which is not a number" in text
    assert browser.find_element(By.ID, "th-v").get_attribute("value") == ""  # not a silent 30
    for t_end, why in (("0", "simulated time = 0 s is outside [0.1, 600] s"),
                       ("100000", "simulated time = 100000 s is outside [0.1, 600] s")):
        type_into(browser.find_element(By.ID, "th-v"), "30")  # a typed speed runs (Run is off while it does)
        type_into(browser.find_element(By.ID, "th-tend"), t_end)
        wait_for(lambda: browser.find_element(By.ID, "th-run").is_enabled(), timeout=120, what="the Run button")
        browser.find_element(By.ID, "th-run").click()
        wait_for(lambda w=why: text_of(browser, "th-error") == w, timeout=10, what=f"the t_end refusal {why}")
    open_page(browser, server, "/bifurcation?configs=original")
    type_into(browser.find_element(By.ID, "bif-vmax"), "")
    browser.find_element(By.ID, "bif-run").click()
    wait_for(lambda: text_of(browser, "bif-error"), timeout=10, what="the empty v_max refusal")
    assert text_of(browser, "bif-error") == "highest V is empty or not a number; enter a number in [1, 500] m/s"
    open_page(browser, server, "/stability-map?shade=foo&overlay=nes,bar")
    assert "shade=foo, which is not a configuration" in text_of(browser, "map-error")
    assert "bar is not a configuration" in text_of(browser, "map-error")
    assert severe(browser) == []


def test_time_history_waits_for_run_and_a_large_start_reaches_the_second_attractor(server, browser):
    open_page(browser, server, "/time-history?config=original&V=50&Fz=850")
    time.sleep(1.5)
    assert browser.find_elements(By.CSS_SELECTOR, "#th-metrics .metric") == []  # no run on load
    assert trace_count(browser, "th-spectrum") == 0  # a message, not bare axes
    assert "appears here" in text_of(browser, "th-spectrum")
    browser.find_element(By.ID, "th-run").click()
    wait_for(lambda: "lateral limit cycle" in text_of(browser, "th-settled"), timeout=120,
             what="the standard start to settle on the lateral cycle")
    assert "psi0 = 0.001 rad" in text_of(browser, "th-settled")
    ticks = browser.execute_script("const g = document.querySelector('#th-spectrum .js-plotly-plot');"
                                   "return g.layout.yaxis.range;")
    assert ticks[0] == pytest.approx(-6) and ticks[1] < 1  # six decades, not twenty
    start = browser.find_element(By.ID, "th-start")
    start.click()
    wait_for(lambda: [o for o in browser.find_elements(By.CSS_SELECTOR, "[role='option']")
                      if "large torsional" in o.text], what="the start options")[0].click()
    wait_for(lambda: browser.find_element(By.ID, "th-psi0").get_attribute("value") == "0.2", timeout=10,
             what="psi0 = 0.2 rad")
    browser.find_element(By.ID, "th-run").click()
    wait_for(lambda: "torsional limit cycle" in text_of(browser, "th-settled"), timeout=120,
             what="the large torsional start to settle on the torsional cycle")
    settled = text_of(browser, "th-settled")
    amplitude = float(settled.split("max |psi| ")[1].split(" rad")[0])
    assert amplitude == pytest.approx(0.20, abs=0.02)
    assert "psi0=0.2" in browser.current_url
    browser.save_screenshot(str(SHOTS / "time-history-second-attractor.png"))
    # Typed values make the choice "typed".
    type_into(browser.find_element(By.ID, "th-lat0"), "0.05")
    wait_for(lambda: "typed" in browser.find_element(By.ID, "th-start").text, timeout=10, what="the typed start")
    assert severe(browser) == []


def test_bifurcation_labels_special_points_with_separate_legends(server, browser):
    open_page(browser, server, "/bifurcation?configs=original,nes&Fz=850")
    browser.find_element(By.ID, "bif-run").click()
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#bif-summary tbody tr"), timeout=180,
             what="the diagram")
    wait_for(lambda: trace_count(browser, "bif-graph") > 10, what="the traces")
    info = browser.execute_script("""
        const g = document.querySelector('#bif-graph .js-plotly-plot');
        const labels = g.data.filter(t => t.meta && t.meta.special_point).map(t => t.text[0]);
        const hovers = g.data.filter(t => t.meta && t.meta.special_point).map(t => t.hovertext[0]);
        const keys = g.data.filter(t => t.showlegend !== false && t.name).map(t => [t.legend || 'legend', t.name,
                                                                                  (t.line || {}).dash || '']);
        return {labels, hovers, keys, titles: [g.layout.legend.title.text, g.layout.legend2.title.text,
                                                g.layout.legend3.title.text]};""")
    assert "LPC1" in info["labels"] and "LPC2" in info["labels"]
    assert any("|Floquet multipliers|" in h and "period =" in h and "V = " in h for h in info["hovers"])
    assert info["titles"] == ["configuration (colour):", "stability (line):", "special points (marker):"]
    by_legend = {}
    for legend, name, dash in info["keys"]:
        by_legend.setdefault(legend, []).append((name, dash))
    assert by_legend["legend"] == [("original", ""), ("NES", "")]  # colour swatches, never dashed
    assert ("unstable", "dash") in by_legend["legend2"]
    assert ("LPC: fold of cycles", "") in by_legend["legend3"]
    assert all(name != "PD" for name, _ in by_legend["legend3"])  # period doubling is never just "PD"
    # The equilibria are one strip per configuration, not four lines on zero.
    strip = browser.execute_script("const g = document.querySelector('#bif-graph .js-plotly-plot');"
                                   "return g.layout.yaxis3.categoryarray;")
    assert strip == ["NES", "original"]
    assert "LPC1" in browser.find_element(By.ID, "bif-summary").text
    browser.save_screenshot(str(SHOTS / "bifurcation-labelled.png"))
    assert severe(browser) == []


def test_map_operating_points_colours_cancel_progress_and_cached_return(server, browser):
    path = "/stability-map?shade=original&fz_min=100&fz_max=400&resolution=3"
    open_page(browser, server, path)
    browser.find_element(By.ID, "map-run").click()
    wait_for(lambda: "3 Fz slices" in text_of(browser, "map-status") or "/3 slices" in text_of(browser, "map-status"),
             timeout=60, interval=0.05, what="progress counted in the slices asked")
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#map-summary tbody tr"), timeout=240,
             what="the map")
    wait_for(lambda: trace_count(browser, "map-graph") > 5, what="the map's traces")
    info = browser.execute_script("""
        const g = document.querySelector('#map-graph .js-plotly-plot');
        const op = g.data.find(t => t.name === 'points A-I');
        const key = n => g.data.find(t => t.legend === 'legend3' && t.name === n).marker.color;
        return {op: op ? op.text : null, torsion: key('Torsion'), both: key('Both'),
                legends: [g.layout.legend.title.text, g.layout.legend2.title.text, g.layout.legend3.title.text]};""")
    assert info["op"] == ["A", "B", "C", "D", "E", "F"]  # inside 100-400 kN, 1-200 m/s
    assert info["torsion"].lower() == "#f0e442" and info["both"].lower() == "#117733"  # Torsion apart from NES orange
    assert info["legends"][0] == "configuration (colour):"
    browser.save_screenshot(str(SHOTS / "stability-map-operating-points.png"))
    # Back on the page later: the cached map is shown without pressing Compute.
    open_page(browser, server, "/")
    open_page(browser, server, path)
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#map-summary tbody tr"), timeout=20,
             what="the cached map on return")
    assert text_of(browser, "map-status") == ""
    # Cancel says "cancelled".
    type_into(browser.find_element(By.ID, "map-res"), "5")
    browser.find_element(By.ID, "map-run").click()
    wait_for(lambda: browser.find_element(By.ID, "map-cancel").is_enabled(), timeout=20, what="Cancel enabled")
    browser.find_element(By.ID, "map-cancel").click()
    wait_for(lambda: text_of(browser, "map-status") == "cancelled", timeout=20, what='"cancelled"')
    time.sleep(1.5)
    assert text_of(browser, "map-status") == "cancelled"  # no late progress line overwrites it
    assert not browser.find_element(By.ID, "map-run").get_attribute("disabled")
    assert severe(browser) == []


def test_study_skips_what_a_parameter_cannot_affect_and_refuses_empty_values(server, browser):
    open_page(browser, server, "/study?parameter=e_p&values=0.0005,0.005&configs=original,nes")
    assert "Skipped: original" in text_of(browser, "study-skipped")
    values = browser.find_element(By.ID, "study-values")
    assert browser.execute_script("return arguments[0].scrollWidth <= arguments[0].clientWidth", values)
    browser.find_element(By.ID, "study-run").click()
    configs = ("return [...document.querySelectorAll('#study-summary tbody tr')].map(r => r.cells[1].innerText);")
    wait_for(lambda: browser.execute_script(configs), timeout=120,
             what=lambda: f"the study table (status: {text_of(browser, 'study-status')!r}, error: "
                          f"{text_of(browser, 'study-error')!r})")
    idle(browser)
    assert browser.execute_script(configs) == ["NES", "NES"]  # original skipped
    browser.find_elements(By.CSS_SELECTOR, "#study-view input")[1].click()
    wait_for(lambda: browser.find_element(By.ID, "study-pivot").is_displayed(), timeout=10, what="the pivot")
    assert not browser.find_element(By.ID, "study-summary").is_displayed()
    assert len(browser.find_elements(By.CSS_SELECTOR, "#study-pivot tbody tr")) == 2
    browser.find_element(By.CSS_SELECTOR, "#study-log input").click()
    wait_for(lambda: browser.execute_script("return document.querySelector('#study-graph .js-plotly-plot')"
                                            ".layout.yaxis4.type") == "log", timeout=10, what="the log axis")
    # the exact curves over the whole range (lines) beside the sampled values (markers)
    modes = browser.execute_script("return document.querySelector('#study-graph .js-plotly-plot').data"
                                   ".map(t => [t.mode, t.x.length]);")
    assert [m for m in modes if m[0] == "lines" and m[1] > 10] and [m for m in modes if m[0] == "markers"]
    type_into(browser.find_element(By.ID, "study-values"), "")
    browser.find_element(By.ID, "study-run").click()
    wait_for(lambda: text_of(browser, "study-error").startswith("Values is empty"), timeout=10, what="the refusal")
    assert browser.find_elements(By.CSS_SELECTOR, "#study-summary tbody tr") == []  # the old table is gone
    assert text_of(browser, "study-status") == ""
    assert severe(browser) == []


def test_devices_current_design_does_not_hide_the_steel_preset(server, browser):
    open_page(browser, server, "/devices")
    wait_for(lambda: trace_count(browser, "dev-pd") >= 3, what="the damper curves")
    names = browser.execute_script("return document.querySelector('#dev-pd .js-plotly-plot').data"
                                   ".map(t => [t.name, t.line.width]);")
    assert names[0] == ["current design (= steel preset)", 7] and ["steel preset", 2] in names


@pytest.mark.parametrize("size", SIZES, ids=lambda s: f"{s[0]}x{s[1]}")
def test_every_page_fits_the_window_and_is_photographed(server, browser, size):
    for name, path in {**PAGES, "ground-run": "/ground-run"}.items():
        open_page(browser, server, path, size)
        time.sleep(0.8)
        browser.save_screenshot(str(SHOTS / f"{name}-{size[0]}x{size[1]}.png"))
        widths = browser.execute_script("return [document.documentElement.scrollWidth, "
                                        "document.documentElement.clientWidth]")
        assert widths[0] <= widths[1], (name, widths)  # no horizontal scrollbar
        assert browser.find_element(By.CSS_SELECTOR, ".navbar").size["height"] < 60, name  # one line: the
        # panel's sticky top sits right under it
        # The panel's column is painted the full height; pages that ignore the design do not show it.
        panel = browser.find_element(By.ID, "design-panel")
        assert panel.is_displayed() == (name not in ("validation", "api")), name
        # Titles sit below the figure toolbar.
        overlaps = browser.execute_script("""
            return [...document.querySelectorAll('.js-plotly-plot')].map(g => {
                const bar = g.querySelector('.modebar'), title = g.querySelector('.gtitle');
                if (!bar || !title) { return false; }
                const a = bar.getBoundingClientRect(), b = title.getBoundingClientRect();
                return a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom; });""")
        assert not any(overlaps), name
        assert not re.search(r"-0(\.0+)?(?![\d.])", browser.find_element(By.TAG_NAME, "main").text), name
    assert severe(browser) == []


def test_plots_shrink_when_the_window_narrows(server, browser):
    open_page(browser, server, "/devices", (1440, 900))
    wait_for(lambda: trace_count(browser, "dev-pd") >= 3, what="the damper curves")
    wide = browser.execute_script("return +document.querySelector('#dev-pd .main-svg').getAttribute('width')")
    browser.set_window_size(1024, 768)
    wait_for(lambda: browser.execute_script("return +document.querySelector('#dev-pd .main-svg')"
                                            ".getAttribute('width')") < wide - 300, timeout=10,
             what="the figure to shrink")
    widths = browser.execute_script("return [document.documentElement.scrollWidth, "
                                    "document.documentElement.clientWidth]")
    assert widths[0] <= widths[1]


def test_paired_fields_share_a_row_and_the_sidebar_collapses(server, browser):
    open_page(browser, server, "/stability-map", (1024, 768))
    tops = [browser.find_element(By.ID, i).location["y"] for i in ("map-fzmin", "map-fzmax")]
    assert tops[0] == tops[1]
    tops = [browser.find_element(By.ID, i).location["y"] for i in ("map-vmin", "map-vmax")]
    assert tops[0] == tops[1]
    width = browser.find_element(By.CSS_SELECTOR, "main.page").size["width"]
    browser.find_element(By.ID, "design-toggle").click()
    wait_for(lambda: not browser.find_element(By.ID, "design-panel").is_displayed(), timeout=5,
             what="the panel to hide")
    assert browser.find_element(By.CSS_SELECTOR, "main.page").size["width"] > width + 200
    browser.save_screenshot(str(SHOTS / "stability-map-1024-panel-hidden.png"))
    browser.find_element(By.ID, "design-toggle").click()
    wait_for(lambda: browser.find_element(By.ID, "design-panel").is_displayed(), timeout=5,
             what="the panel to show again")
    # The panel's white column runs the full height of a long page.
    open_page(browser, server, "/api", (1024, 768))
    open_page(browser, server, "/bifurcation", (1024, 768))
    image = browser.execute_script("return getComputedStyle(document.querySelector('.body')).backgroundImage")
    assert "linear-gradient" in image
    assert severe(browser) == []


def test_an_nes_rotation_beyond_the_cubic_is_said_and_the_exact_torque_is_a_choice(server, browser):
    """Point D with the NES (50 m/s, 350 kN): the NES relative rotation reaches about 0.16 rad, beyond the
    cubic's 1 % range (0.094 rad for the nominal design); the run says so at once, and the exact torque,
    chosen on the page, answers without the warning."""
    open_page(browser, server, "/time-history?config=nes&V=50&Fz=350&t_end=20&run=1")
    said = wait_for(lambda: text_of(browser, "th-error"), timeout=120, what="the run's warning")
    assert "NES rotation beyond the cubic's range" in said and "0.0939 rad" in said
    assert "cubic fit\nNES torque" in text_of(browser, "th-metrics")
    exact = wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#th-exact input[value='exact']"),
                     what="the exact torque choice")[0]
    exact.click()
    wait_for(lambda: "exact_nes=1" in browser.current_url, timeout=10, what="the address to carry the choice")
    idle(browser)
    browser.find_element(By.ID, "th-run").click()
    wait_for(lambda: "exact\nNES torque" in text_of(browser, "th-metrics"), timeout=180, what="the exact run")
    assert text_of(browser, "th-error") == ""  # within the exact torque's validity: nothing to warn of
    browser.save_screenshot(str(SHOTS / "time-history-exact-nes-1440.png"))
    # The bifurcation page offers the same choice and says the same of the cubic's diagram.
    open_page(browser, server, "/bifurcation")
    assert browser.find_elements(By.CSS_SELECTOR, "#bif-exact input[value='exact']")
    assert browser.find_elements(By.CSS_SELECTOR, "#gr-exact input") == []  # one page's ids, not another's
    assert severe(browser) == []
