"""The Ground run page in real headless Chromium against gunicorn (the set-up of test_browser.py)."""

from __future__ import annotations

import csv
import io

import pytest

pytest.importorskip("selenium")
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402

from browser import (DOWNLOADS, SHOTS, browser_fixture, idle, severe, text_of, trace_count, type_into,  # noqa: E402
                     wait_for)

browser = browser_fixture("chromium-profile", "1500,1100", DOWNLOADS)  # the profile of test_browser.py

NAMES = ["original", "NES", "PD", "NES + PD"]


def _summary(driver) -> list[list[str]]:
    """The summary table's cells, read in one script (no stale references while Dash redraws it)."""
    return driver.execute_script(
        "return Array.from(document.querySelectorAll('#gr-summary-table tbody tr'))"
        ".map(r => Array.from(r.cells).map(c => c.innerText));")



JOB_WAIT = 400  # s: the longest wait for the page's four ground-run jobs


def _edit_cell(driver, row: int, column: str, text: str) -> None:
    cell = driver.find_elements(By.CSS_SELECTOR, f"#gr-table td[data-dash-column='{column}']")[row]
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", cell)  # not under the sticky bar
    cell.click()  # selects it; typing then replaces its value
    ActionChains(driver).send_keys(text).send_keys(Keys.ENTER).perform()


def test_ground_run_page_runs_the_presets_and_a_table(server, browser):
    browser.get_log("browser")
    browser.set_window_size(1440, 900)
    browser.get(server.base + "/ground-run")
    # Nothing runs on opening (tests/ui/test_browser.py checks the job store): Run starts the four
    # ground runs as background jobs on the shared server's two job slots, bounded generously for a
    # loaded machine, not timed.
    wait_for(lambda: "Press Run" in text_of(browser, "gr-plane"), what="the plane waiting for Run")
    idle(browser)
    browser.find_element(By.ID, "gr-run").click()
    rows = wait_for(lambda: (s := _summary(browser)) and len(s) == 4 and s, timeout=JOB_WAIT,
                    what="the take-off of the four configurations")
    assert [r[0] for r in rows] == NAMES
    assert float(rows[0][1]) > float(rows[3][1].split()[0]) > 0  # NES + PD spends less time in shimmy
    wait_for(lambda: trace_count(browser, "gr-time") == 8 and trace_count(browser, "gr-speed") == 8,
             what="two envelopes of four configurations against t and V")
    assert trace_count(browser, "gr-plane") >= 4  # Hopf curve(s), trajectory, shimmy stretch, start, crossings
    assert "take-off preset" in browser.find_element(By.ID, "gr-source").text
    idle(browser)
    browser.save_screenshot(str(SHOTS / "ground-run-1440.png"))
    origins = browser.execute_script("return performance.getEntriesByType('resource').map(e => e.name);")
    assert all(u.startswith(server.base) for u in origins)
    assert severe(browser) == []

    # The downloads serialise what is drawn.
    for f in DOWNLOADS.glob("ground_run_*"):
        f.unlink()
    browser.find_element(By.ID, "gr-csv").click()
    path = DOWNLOADS / "ground_run_takeoff.csv"
    wait_for(lambda: path.exists() and path.stat().st_size > 0, timeout=20, what="the CSV download")
    table = list(csv.reader(io.StringIO(path.read_text())))
    assert table[0][:4] == ["config", "t_s", "V_m_s", "Fz_kN"]
    assert {r[0] for r in table[1:]} == {"original", "nes", "pd", "nes_pd"}

    # An edited table runs instead of the preset: start at 30 m/s (inside the unstable region).
    before = _summary(browser)
    _edit_cell(browser, 0, "V", "30")
    wait_for(lambda: "your table" in text_of(browser, "gr-source"), timeout=10, what="the table to be the profile")
    browser.find_element(By.ID, "gr-run").click()
    wait_for(lambda: (s := _summary(browser)) and s != before and s, timeout=JOB_WAIT, what="the run of the table")
    assert severe(browser) == []

    # A bad row is refused, naming its row and column.
    _edit_cell(browser, 1, "V", "600")
    browser.find_element(By.ID, "gr-run").click()
    # (the error line may still carry the last run's warnings: wait for the refusal itself)
    message = wait_for(lambda: "profile[1]" in text_of(browser, "gr-error") and text_of(browser, "gr-error"),
                       timeout=20, what="the refusal")
    assert "profile[1].V=600" in message and "row 2 of the table" in message and "[1, 500] m/s" in message

    # The landing roll from the URL, at the smaller window.
    browser.set_window_size(1024, 768)
    browser.get(server.base + "/ground-run?preset=landing&config=nes")
    wait_for(lambda: "landing roll preset" in text_of(browser, "gr-source"), timeout=30, what="the landing preset")
    idle(browser)
    assert not _summary(browser)  # not run on opening
    browser.find_element(By.ID, "gr-run").click()
    rows = wait_for(lambda: (s := _summary(browser)) and len(s) == 4 and s, timeout=JOB_WAIT, what="the landing roll")
    assert "Hopf curves of NES" in browser.find_element(By.CSS_SELECTOR, "#gr-plane .gtitle").text
    idle(browser)
    browser.save_screenshot(str(SHOTS / "ground-run-1024.png"))
    assert severe(browser) == []
    browser.set_window_size(1500, 1100)


def test_ground_run_address_values_are_refused_not_replaced(server, browser):
    """Values from the address that are not usable are named where the user looks, in the
    field's unit; a threshold that is not a number leaves its box empty and nothing runs from it."""
    browser.get(server.base + "/ground-run?preset=cruise&psi_thr=abc&lat_thr=5000")
    error = wait_for(lambda: "".join(e.text for e in browser.find_elements(By.ID, "gr-address")) or None,
                     what="the refusal")
    assert "preset=cruise" in error and "psi_thr=abc" in error and "not a number" in error
    assert "lat_thr=5000" in error and "mm" in error
    # nothing is run on load from what the address could not give (the line above says why) ...
    idle(browser)
    assert not browser.find_elements(By.CSS_SELECTOR, "#gr-summary tbody tr")
    # ... and Run refuses it in the box's unit
    browser.find_element(By.ID, "gr-run").click()
    refusal = wait_for(lambda: "".join(e.text for e in browser.find_elements(By.ID, "gr-error")) or None,
                       what="the refused run")
    assert "threshold |psi|" in refusal and "rad" in refusal
    assert browser.find_element(By.ID, "gr-psi-thr").get_attribute("value") == ""


def test_ground_run_page_runs_a_kick_and_refuses_it_in_its_unit(server, browser):
    """The touchdown scenario from the address fills the kick boxes; Run shows what followed the kick in the
    table's last column; a yaw kick beyond 0.5 rad is refused in the box's unit."""
    browser.get(server.base + "/ground-run?preset=touchdown_yaw")
    wait_for(lambda: "Touchdown with yaw" in text_of(browser, "gr-kick-note"), timeout=30, what="the scenario's note")
    assert browser.find_element(By.ID, "gr-kick-size").get_attribute("value") == "0.05"
    assert browser.find_element(By.ID, "gr-kick-when").get_attribute("value") == "0"
    assert "landing roll preset" in text_of(browser, "gr-source")
    idle(browser)
    browser.find_element(By.ID, "gr-run").click()
    rows = wait_for(lambda: (s := _summary(browser)) and len(s) == 4 and s, timeout=JOB_WAIT,
                    what="the landing roll with the touchdown yaw")
    header = browser.execute_script("return Array.from(document.querySelectorAll('#gr-summary-table th'))"
                                    ".map(c => c.innerText);")
    assert header[-1] == "after the kick (psi +0.05 rad at 0 s, 65 m/s)"
    assert all("shimmy" in r[-1] and "s in shimmy against no kick" in r[-1] for r in rows)
    assert severe(browser) == []
    box = browser.find_element(By.ID, "gr-kick-size")
    type_into(box, "0.8")
    browser.find_element(By.ID, "gr-run").click()
    # (the error line may still carry the last run's warnings: wait for the refusal itself)
    message = wait_for(lambda: "kick size" in text_of(browser, "gr-error") and text_of(browser, "gr-error"),
                       timeout=20, what="the refusal")
    assert "kick size (yaw angle psi) = 0.8 rad is outside [-0.5, 0.5] rad" in message
