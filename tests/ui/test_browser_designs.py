"""Design sessions in real headless Chromium against gunicorn (the set-up of test_browser.py): designs
saved in the browser reopen to the same figures from their saved entry, their JSON file and their
link; a bad file is refused by name; two designs compared on a page both show. The Overview answers
at once and the Bifurcation page's comparison is one diagram per design (a few seconds cold), so the
added time stays small."""

from __future__ import annotations

import json
from urllib.parse import parse_qs, urlsplit

import pytest

from shimmy.model.parameters import PARAMETER_SPECS

pytest.importorskip("selenium")
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402

from browser import (DOWNLOADS, SHOTS, browser_fixture, by_id, idle, open_page, severe, text_of,  # noqa: E402
                     slider_handle, trace_count, type_into, wait_for)

browser = browser_fixture("chromium-profile", "1500,1100", DOWNLOADS)  # the profile of test_browser.py

A = ("A wide track", "/?r2=0.085")
B = ("B stiff spring", "/?r2=0.075&k_s=1300000")


def _figures(driver):
    """What the Overview shows of a design: its Hopf table and its NES growth-rate curve."""
    return wait_for(lambda: driver.execute_script("""
        const rows = [...document.querySelectorAll('#ov-hopf-table tbody tr')].map(r => r.innerText);
        const g = document.querySelector('#ov-growth .js-plotly-plot');
        const t = g && g.data ? g.data.find(t => t.name === 'NES') : null;
        return rows.length === 4 && t ? JSON.stringify([rows, t.y]) : null;"""), what="the Overview's figures")


def _saved(driver):
    """[(name, detail)] of the saved designs in the panel."""
    return driver.execute_script("""return [...document.querySelectorAll('#designs-list .saved-row')].map(r =>
        [r.querySelector('input').value, r.querySelector('.saved-detail').innerText]);""")


def _click_row(driver, name: str, label: str) -> None:
    """Press a saved design's button, found and clicked in one script (the list is redrawn after
    every change: an element found earlier may be gone)."""
    idle(driver)
    wait_for(lambda: driver.execute_script("""
        const row = [...document.querySelectorAll('#designs-list .saved-row')]
            .find(r => r.querySelector('input').value === arguments[0]);
        const button = row ? [...row.querySelectorAll('button')].find(b => b.innerText === arguments[1]) : null;
        if (button) { button.click(); }
        return !!button;""", name, label), timeout=10, what=f"the {label} button of {name!r}")


def _tick(driver, *names: str) -> None:
    """Tick designs under Compare (found and clicked in one script; done once each is ticked)."""
    idle(driver)
    wait_for(lambda: driver.execute_script("""
        const labels = [...document.querySelectorAll('#design-compare label')];
        let done = true;
        for (const name of arguments[0]) {
            const label = labels.find(l => l.innerText.trim() === name);
            if (!label) { done = false; continue; }
            if (!label.querySelector('input').checked) { label.click(); done = false; }
        }
        return done;""", list(names)), timeout=10, interval=0.3, what=f"{names} ticked")


def _save(driver, server, name: str, path: str) -> None:
    open_page(driver, server, path)
    type_into(by_id(driver, "design-name"), name)
    by_id(driver, "design-save").click()
    wait_for(lambda: any(n == name for n, _ in _saved(driver)), timeout=10, what=f"{name!r} in the saved list")


def _reopened(driver, path: str, **design: str) -> None:
    """Wait for the page load an Open started: the page's address with the design's keys (and no
    other design key), and the page saying what it opened."""
    def loaded():
        url = urlsplit(driver.current_url)
        query = {k: v[-1] for k, v in parse_qs(url.query).items()}
        keys = {k: v for k, v in query.items() if k in PARAMETER_SPECS or k == "material"}
        return (url.path == path and keys == design and text_of(driver, "designs-message").startswith("Opened"))

    wait_for(loaded, timeout=20, what=f"the page to load {path} with {design}")
    idle(driver)


def _fresh(driver, server) -> None:
    """No saved designs and nothing ticked (the profile outlives a run)."""
    open_page(driver, server, "/")
    driver.execute_script("localStorage.clear(); sessionStorage.clear();")


def _upload(driver, path) -> None:
    driver.find_element(By.CSS_SELECTOR, "#design-upload input[type=file]").send_keys(str(path))


def test_a_saved_design_reopens_to_the_same_figures(server, browser, tmp_path):
    _fresh(browser, server)
    _save(browser, server, *A)
    assert text_of(browser, "designs-message") == "Saved 'A wide track' in this browser (1 saved)."
    shown_a = _figures(browser)
    link = wait_for(lambda: by_id(browser, "design-link").get_attribute("value"), what="the link")
    assert link == server.base + "/?r2=0.085&Fz=150&vmax=200"
    (DOWNLOADS / "A_wide_track.json").unlink(missing_ok=True)
    by_id(browser, "design-download-json").click()
    file_a = DOWNLOADS / "A_wide_track.json"
    wait_for(file_a.exists, timeout=20, what="the design file")
    data = json.loads(file_a.read_text())
    assert data["name"] == "A wide track" and data["parameters"]["r2"] == 0.085 and len(data["parameters"]) == 38
    _save(browser, server, *B)
    shown_b = _figures(browser)
    assert shown_b != shown_a
    assert _saved(browser) == [["A wide track", "steel: r2 = 0.085 m"],
                               ["B stiff spring", "● shown now · steel: r2 = 0.075 m, k_s = 1.3e+06 N/m"]]
    browser.save_screenshot(str(SHOTS / "designs-panel-1440x900.png"))

    # from its saved entry
    _click_row(browser, "A wide track", "Open")
    _reopened(browser, "/", r2="0.085")
    assert _figures(browser) == shown_a
    assert by_id(browser, "design-name").get_attribute("value") == "A wide track"
    assert _saved(browser)[0][1].startswith("● shown now")

    # from its file (on a page showing B)
    open_page(browser, server, B[1])
    _upload(browser, file_a)
    _reopened(browser, "/", r2="0.085")
    assert _figures(browser) == shown_a
    assert "Opened 'A wide track' from A_wide_track.json" in text_of(browser, "designs-message")

    # from its link
    open_page(browser, server, B[1])
    browser.get(link)
    idle(browser)
    assert _figures(browser) == shown_a

    # a bad file is refused naming the field, the value and the range; nothing of it is applied
    bad = tmp_path / "bad.json"
    data["parameters"].update({"r2": 0.5, "k_sx": 1.2e6})
    bad.write_text(json.dumps(data))
    url = browser.current_url
    _upload(browser, bad)
    wait_for(lambda: "Refused (bad.json)" in text_of(browser, "designs-message"), timeout=10, what="the refusal")
    message = text_of(browser, "designs-message")
    assert "r2 = 0.5 m is out of range; allowed: a number in [0.07, 0.09] m" in message
    assert "unknown parameter 'k_sx' (did you mean k_s, k_psi?)" in message
    assert browser.current_url == url and len(_saved(browser)) == 2
    browser.set_window_size(1024, 768)
    wait_for(lambda: browser.execute_script("return document.documentElement.scrollWidth <= "
                                            "document.documentElement.clientWidth"), timeout=10,
             what="the page to fit 1024 px")
    browser.execute_script("document.getElementById('designs-message').scrollIntoView({block: 'center'})")
    browser.save_screenshot(str(SHOTS / "designs-refused-file-1024x768.png"))

    # rename, delete
    type_into(by_id(browser, '{"id":"d2","type":"saved-name"}'), "B renamed")
    wait_for(lambda: [n for n, _ in _saved(browser)] == ["A wide track", "B renamed"], timeout=10,
             what="the rename")
    _click_row(browser, "B renamed", "Delete")
    wait_for(lambda: [n for n, _ in _saved(browser)] == ["A wide track"], timeout=10, what="the deletion")
    assert text_of(browser, "designs-message") == "Deleted 'B renamed'."

    # the refused file, corrected and chosen again, is read again
    del data["parameters"]["k_sx"]
    data["parameters"]["r2"] = 0.0855
    bad.write_text(json.dumps(data))
    _upload(browser, bad)
    _reopened(browser, "/", r2="0.0855")
    assert "Replaced the saved design 'A wide track'" in text_of(browser, "designs-message")
    assert severe(browser) == []


def _compare_names(driver) -> list[list[str]]:
    """[legend names of the comparison's colour legend, the table's design columns]."""
    return driver.execute_script("""
        const g = document.querySelector('#bifc-graph .js-plotly-plot');
        const keys = g && g.data ? g.data.filter(t => t.showlegend && (t.legend || 'legend') === 'legend')
                                         .map(t => t.name) : [];
        const head = [...document.querySelectorAll('#bifc-summary thead th')].slice(1)
                         .map(th => th.innerText.replace('■ ', '').replace(' (reference)', ''));
        return [keys, head];""")


def _cycles(driver, graph: str, name: str):
    """The y values of the limit-cycle lines a diagram draws for ``name`` (a configuration or a design)."""
    return driver.execute_script("""
        const g = document.querySelector(`#${arguments[0]} .js-plotly-plot`);
        return g.data.filter(t => (t.hovertemplate || '').startsWith(arguments[1] + ': limit cycle'))
                     .map(t => t.y);""", graph, name)


def test_two_designs_compared_on_the_bifurcation_page_both_show(server, browser):
    _fresh(browser, server)
    page = "/bifurcation?configs=nes&compare_config=nes"
    _save(browser, server, A[0], page + "&r2=0.085")
    _save(browser, server, B[0], page + "&r2=0.075&k_s=1300000")
    _tick(browser, A[0], B[0])
    wait_for(lambda: text_of(browser, "bifc-designs").startswith("Comparing: ■ A wide track (reference) ■ B stiff"),
             timeout=10, what="the designs to compare")
    by_id(browser, "bifc-run").click()
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#bifc-summary tbody tr"), timeout=120,
             what="the comparison")
    wait_for(lambda: trace_count(browser, "bifc-graph") > 6, what="the comparison's traces")
    assert _compare_names(browser) == [[A[0], B[0]], [A[0], B[0]]]
    strip = browser.execute_script("return document.querySelector('#bifc-graph .js-plotly-plot')"
                                   ".layout.yaxis3.categoryarray")
    assert strip == [B[0], A[0]]  # each design's x = 0 strip: its Hopf interval
    hopf = browser.execute_script("return [...document.querySelectorAll('#bifc-summary tbody tr')]"
                                  ".find(r => r.cells[0].innerText.startsWith('Hopf points')).innerText")
    assert hopf.count("6.7") >= 2 and "Δ" in hopf  # both designs' Hopf points, the change of B
    assert _cycles(browser, "bifc-graph", A[0]) and _cycles(browser, "bifc-graph", B[0])
    browser.execute_script("document.getElementById('bifc-graph').scrollIntoView()")
    browser.save_screenshot(str(SHOTS / "designs-compare-bifurcation.png"))

    # Reopened, A shows its own diagram at once (the cache has it: the same request) and the comparison stays.
    compared_a = _cycles(browser, "bifc-graph", A[0])
    _click_row(browser, A[0], "Open")
    _reopened(browser, "/bifurcation", r2="0.085")
    wait_for(lambda: trace_count(browser, "bif-graph") > 4, timeout=20, what="A's cached diagram")
    assert _cycles(browser, "bif-graph", "NES") == compared_a
    wait_for(lambda: trace_count(browser, "bifc-graph") > 6, timeout=20, what="the cached comparison")

    # The Overview compares the same two at once: their Hopf intervals side by side.
    open_page(browser, server, "/")
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, "#ov-cmp-summary tbody tr"), timeout=20,
             what="the Overview's comparison")
    columns = browser.execute_script("return [...document.querySelectorAll('#ov-cmp-summary thead th')]"
                                     ".map(th => th.innerText)")
    assert columns == ["figure", "■ A wide track (reference)", "■ B stiff spring"]
    assert trace_count(browser, "ov-cmp-graph") > 8
    assert severe(browser) == []


def _comparison(driver):
    """The Overview comparison's table rows (text), once it has them."""
    return driver.execute_script("return [...document.querySelectorAll('#ov-cmp-summary tbody tr')]"
                                 ".map(r => r.innerText);")


def test_the_overview_comparison_follows_the_slider_only_with_the_current_design_ticked(server, browser):
    """A comparison with the current design ticked follows a slider step; one of saved designs alone does
    not depend on it (the page then sends no request for it: its callback's design input only fires while
    the current design is ticked)."""
    _fresh(browser, server)
    _save(browser, server, *A)
    open_page(browser, server, "/")
    _tick(browser, "current design", A[0])
    first = wait_for(lambda: len(_comparison(browser)) > 1 and _comparison(browser), timeout=20,
                     what="the comparison of the current design and A")
    handle = slider_handle(browser, "r2")
    handle.click()
    for _ in range(10):
        handle.send_keys(Keys.ARROW_LEFT)
    moved = wait_for(lambda: (rows := _comparison(browser)) != first and rows, timeout=20,
                     what="the comparison to follow the current design")
    assert len(moved) == len(first)
    # saved designs alone: a step sends nothing for the comparison and leaves it as it is
    _save(browser, server, *B)
    open_page(browser, server, "/")
    _tick(browser, A[0], B[0])
    idle(browser)
    browser.execute_script("""const l = [...document.querySelectorAll('#design-compare label')]
        .find(l => l.innerText.trim() === 'current design'); if (l.querySelector('input').checked) { l.click(); }""")
    idle(browser)
    saved_only = wait_for(lambda: (rows := _comparison(browser)) and "B stiff spring" in text_of(
        browser, "ov-cmp-designs") and rows, timeout=20, what="the comparison of A and B")
    assert "current design" not in text_of(browser, "ov-cmp-designs")
    browser.execute_script("""window.__asked = []; const f = window.fetch;
        window.fetch = function(url, opts) { window.__asked.push((opts && opts.body) || ''); return f.apply(this, arguments); };""")
    handle = slider_handle(browser, "r2")
    handle.click()
    for _ in range(5):
        handle.send_keys(Keys.ARROW_LEFT)
    wait_for(lambda: any("ov-growth.figure" in b for b in browser.execute_script("return window.__asked;")),
             timeout=20, what="the growth figure's request")
    idle(browser)
    asked = browser.execute_script("return window.__asked;")
    assert not any("ov-cmp-graph.figure" in b for b in asked), [json.loads(b).get("changedPropIds") for b in asked if b]
    assert _comparison(browser) == saved_only
    assert severe(browser) == []
