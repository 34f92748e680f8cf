"""Kicks of any kind in the Time history page's margins, in real Chromium against gunicorn (tests/ui/browser.py):
at original (50 m/s, 550 kN) the kick along a typed mix of yaw angle and rate, added to the lateral cycle the
standard start reaches; the table gives the torsional cycle's smallest kick in J with its multiple of the mix and
its phase, and its Run button runs the time history from that whole state, which ends torsional. Bounded: one
point; waits, no timing assertions."""

from __future__ import annotations

import re

import pytest

selenium = pytest.importorskip("selenium")
from selenium.webdriver.common.by import By  # noqa: E402

from browser import (SHOTS, browser_fixture, by_id, idle, open_page, severe, table_rows, text_of,  # noqa: E402
                     type_into, wait_for)

browser = browser_fixture("chromium-margins", "1440,900")
POINT = "/time-history?config=original&V=50&Fz=550"


def choose(browser, dropdown_id: str, label: str) -> None:
    """Pick the option ``label`` of a Dash dropdown as a user does: open it, click the option."""
    box = browser.find_element(By.ID, dropdown_id)
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'})", box)
    box.click()
    option = wait_for(lambda: next((o for o in browser.find_elements(By.CSS_SELECTOR, "[role='option']")
                                    if o.text.strip() == label), None), timeout=10, what=f"the option {label!r}")
    option.click()
    wait_for(lambda: label in box.text, timeout=10, what=f"{dropdown_id} to show {label!r}")


def _rows(browser) -> list[list[str]]:
    return table_rows(browser, "#thm-summary tbody tr")


def test_a_mixed_kick_from_the_standard_starts_cycle_and_a_run_from_that_state(server, browser):
    open_page(browser, server, POINT, clear_log=True)
    assert browser.find_element(By.ID, "thm-mix").get_attribute("disabled")  # read only with a mix
    choose(browser, "thm-direction", "a mix (typed beside)")
    wait_for(lambda: not browser.find_element(By.ID, "thm-mix").get_attribute("disabled"), timeout=10,
             what="the mix box to open")
    type_into(browser.find_element(By.ID, "thm-mix"), "psi=0.01, dpsi=0.1")
    choose(browser, "thm-origin", "the standard start's attractor")
    browser.find_element(By.ID, "thm-run").click()
    wait_for(lambda: _rows(browser), timeout=240, what=lambda: "the margins' table (status: "
             + text_of(browser, "thm-status") + text_of(browser, "thm-error") + ")")
    table = text_of(browser, "thm-table")
    assert "kicks along the mix psi=0.01,dpsi=0.1 added to the lateral limit cycle the standard start reaches" in table
    rows = _rows(browser)
    torsional = next(r for r in rows if r[0].startswith("torsional limit cycle"))
    kick = re.match(r"([0-9.e+]+) ± \S+ J \(([0-9.]+) × the mix\) at ([0-9.]+) of the period", torsional[3])
    assert kick, torsional[3]
    assert float(kick.group(1)) > 100.0 and float(kick.group(2)) > 1.0 and 0.0 <= float(kick.group(3)) < 1.0
    assert torsional[4].startswith("yes")
    idle(browser)
    browser.execute_script("document.getElementById('thm-summary').scrollIntoView({block: 'center'})")
    browser.save_screenshot(str(SHOTS / "time-history-mixed-kick-1440.png"))
    browser.set_window_size(1024, 768)
    wait_for(lambda: browser.execute_script("return document.documentElement.scrollWidth <= "
                                            "document.documentElement.clientWidth"), timeout=10,
             what="the page to fit 1024 px")
    browser.execute_script("document.getElementById('thm-summary').scrollIntoView({block: 'center'})")
    idle(browser)
    browser.save_screenshot(str(SHOTS / "time-history-mixed-kick-1024.png"))
    browser.set_window_size(1440, 900)
    button = by_id(browser, '{"index":%d,"type":"thm-run"}' % rows.index(torsional))
    assert button.text == "Run from this kick"
    button.click()
    wait_for(lambda: "torsional limit cycle" in text_of(browser, "th-settled"), timeout=240,
             what=lambda: "the run from the kick to end torsional (" + text_of(browser, "th-settled")
             + text_of(browser, "th-status") + ")")
    settled = text_of(browser, "th-settled")
    assert settled.startswith("From the margins' kick (psi ") and "dpsi " in settled and "settled on" in settled
    psi0 = float(browser.find_element(By.ID, "th-psi0").get_attribute("value"))
    assert f"psi {psi0:.4g} rad" in settled
    idle(browser)
    browser.save_screenshot(str(SHOTS / "time-history-mixed-kick-run-1440.png"))
    # a typed start: the boxes' values again, not the kick's state
    type_into(browser.find_element(By.ID, "th-psi0"), "0.002")
    browser.find_element(By.ID, "th-run").click()
    wait_for(lambda: text_of(browser, "th-settled").startswith("From psi0 = 0.002 rad, l_g delta0 = "), timeout=240,
             what=lambda: "the run from the typed start (" + text_of(browser, "th-settled") + ")")
    assert severe(browser) == []
