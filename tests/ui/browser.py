"""What the browser tests share: headless Chromium (Debian chromium + chromedriver, installed by the
set-up when missing and allowed: CI runs as root), its fixtures, and the waits and reads the tests
make of a page. The test modules import it (pytest puts their folder on sys.path).
"""

from __future__ import annotations

import json

import os
import time
from pathlib import Path

import pytest
from conftest import apt_install

pytest.importorskip("selenium")
from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.common.exceptions import StaleElementReferenceException  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SHOTS = ROOT / "screenshots"  # screenshots for a person to look at (not committed)
#: pytest-xdist's worker ("gw0", ...; "" without xdist): each worker has its own profiles and downloads
WORKER = os.environ.get("PYTEST_XDIST_WORKER", "")
DOWNLOADS = ROOT / ".pytest_cache" / ("downloads-" + WORKER if WORKER else "downloads")
CHROMIUM, CHROMEDRIVER = "/usr/bin/chromium", "/usr/bin/chromedriver"
PAGES = {"overview": "/", "devices": "/devices", "time-history": "/time-history", "bifurcation": "/bifurcation",
         "stability-map": "/stability-map", "ground-run": "/ground-run", "study": "/study", "design": "/design",
         "validation": "/validation", "api": "/api"}


def _ensure_chromium() -> None:
    apt_install(["chromium", "chromium-driver"], lambda: os.path.exists(CHROMIUM) and os.path.exists(CHROMEDRIVER))


def chromium(profile: str, window: str, downloads: Path | None = None):
    """Headless Chromium on a profile of its own (``profile`` under .pytest_cache, one per xdist
    worker), started once per session (``browser_fixture``): a second browser on the same profile,
    started while the first is still closing, would hand its pages to that one."""
    _ensure_chromium()
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--disable-dev-shm-usage", f"--window-size={window}"):
        opts.add_argument(arg)
    opts.add_argument(f"--user-data-dir={ROOT / '.pytest_cache' / (profile + '-' + WORKER if WORKER else profile)}")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    if downloads is not None:
        downloads.mkdir(parents=True, exist_ok=True)
        opts.add_experimental_option("prefs", {"download.default_directory": str(downloads),
                                               "download.prompt_for_download": False})
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    driver.set_page_load_timeout(60)
    SHOTS.mkdir(exist_ok=True)
    return driver


def browser_fixture(profile: str, window: str, downloads: Path | None = None):
    """A module's ``browser`` fixture: Chromium on ``profile`` at ``window`` ("W,H"). Started once per
    session (per xdist worker) for each (profile, window, downloads) and quit at its end (the
    ``browsers`` fixture of tests/conftest.py); a module that gets one another module used finds it
    on a blank page at ``window``, its console read."""

    @pytest.fixture(scope="module")
    def browser(browsers):
        key = (profile, window, str(downloads))
        driver = browsers.get(key)
        if driver is None:
            driver = browsers[key] = chromium(profile, window, downloads)
        else:
            driver.set_window_size(*(int(n) for n in window.split(",")))
            driver.get("about:blank")
            driver.get_log("browser")
        return driver

    return browser


def severe(driver) -> list[str]:
    """The console's errors since it was last read."""
    return [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]


#: The shortest a wait waits before it fails, whatever ``timeout`` a test gives: a callback round trip
#: that takes 0.1 s on a quiet machine took over 10 s in CI with both cores taken by the other xdist
#: worker, Chromium and the server's jobs. A wait returns as soon as its condition holds, so this only
#: bounds how long a real failure takes to be reported: a wait is no speed test (speeds are measured
#: by benchmarks/, in medians, not by a test's timeout on a shared machine).
MIN_WAIT_S = 45.0


def wait_for(predicate, timeout=60.0, interval=0.1, what="condition"):
    """``predicate()`` once it is true; ``what`` (text, or a function giving it when the wait fails:
    the page's state then) names what was waited for. An element the page replaced while the predicate
    read it (Dash re-rendered it: StaleElementReferenceException) counts as not yet. ``timeout`` (s)
    is raised to :data:`MIN_WAIT_S`."""
    deadline = time.time() + max(timeout, MIN_WAIT_S)
    while time.time() < deadline:
        try:
            value = predicate()
        except StaleElementReferenceException:
            value = None
        if value:
            return value
        time.sleep(interval)
    raise AssertionError(f"timed out waiting for {what() if callable(what) else what}")


def idle(driver, timeout=60.0):
    """Dash has no callback in flight (the renderer sets data-dash-is-loading on busy components)."""
    wait_for(lambda: not driver.find_elements(By.CSS_SELECTOR, "[data-dash-is-loading='true']"), timeout,
             what="Dash to be idle")


def open_page(driver, server, path, size=(1440, 900), *, clear_log=False, wait_idle=True):
    """Load ``path`` (at the window ``size``, unless None) and wait for its header and, unless told
    not to, for Dash to be idle; ``clear_log``: drop the console's messages first (those the page
    then logs are its own)."""
    if clear_log:
        driver.get_log("browser")
    if size is not None:
        driver.set_window_size(*size)
    driver.get(server.base + path)
    wait_for(lambda: driver.find_elements(By.CSS_SELECTOR, ".page-header h1"), what="the page header")
    if wait_idle:
        idle(driver)


def table_rows(driver, css) -> list[list[str]]:
    """The text of each cell of each row matched by ``css`` (e.g. "#id tbody tr"), read in one script
    so that a table Dash re-renders meanwhile is never half read (no stale elements)."""
    return driver.execute_script("return [...document.querySelectorAll(arguments[0])]"
                                 ".map(r => [...r.querySelectorAll('td')].map(c => c.innerText.trim()));", css)


def by_id(driver, element_id):
    """An element by id (pattern-matching ids are JSON, not valid CSS)."""
    return driver.execute_script("return document.getElementById(arguments[0])", element_id)


def slider_handle(driver, name: str | None = None):
    """The handle (role slider) of parameter ``name``'s slider, or of the page's first slider; waited for:
    dcc.Slider's code is a chunk loaded lazily, under load drawn after the page's figures."""
    def find():
        root = driver if name is None else by_id(driver, pattern(name, "param"))
        found = [] if root is None else root.find_elements(By.CSS_SELECTOR, "[role='slider']")
        return found[0] if found else None

    return wait_for(find, what=f"the {name or 'first'} slider")


def pattern(name: str, kind: str) -> str:
    """The DOM id of a pattern-matching component {"type": kind, "name": name}."""
    return '{"name":"%s","type":"%s"}' % (name, kind)


def text_of(driver, element_id: str) -> str:
    """The text of an element, empty until the page has rendered it."""
    return driver.execute_script("const e = document.getElementById(arguments[0]); return e ? e.innerText : '';",
                                 element_id)


def type_into(element, value: str) -> None:
    """Replace a box's content and leave it (a debounced box sends its value on blur)."""
    element.click()
    element.send_keys(Keys.CONTROL, "a")
    element.send_keys(Keys.BACKSPACE)
    if value:
        element.send_keys(value)
    element.send_keys(Keys.TAB)


def trace_count(driver, graph_id: str) -> int:
    """Traces Plotly has drawn in a dcc.Graph (0 until it has drawn: the figure can lag the tables)."""
    return driver.execute_script(f"const g = document.querySelector('#{graph_id} .js-plotly-plot');"
                                 "return g && g.data ? g.data.length : 0;")


def job_records(server) -> dict[str, dict]:
    """Every job the server's job store holds, by id (queued, running and finished ones)."""
    return server.job_records()


def on_figure(driver, graph_id: str, script: str):
    """``script`` on the drawn figure ``g`` of a dcc.Graph (null until Plotly has drawn it)."""
    return driver.execute_script(f"const g = document.querySelector('#{graph_id} .js-plotly-plot');"
                                 f"if (!g || !g.data) {{ return null; }} {script}")


#: The page's own record of a figure's titles (title and subtitle, joined by ' | '), read every 25 ms, each with
#: the value of an expression on the figure ``g`` at that time: a state that lasts less than a WebDriver round
#: trip on a loaded machine (a sketch's title while a warm map is made) is seen all the same.
_RECORD_TITLES = """
const id = arguments[0], extra = new Function('g', 'return (' + arguments[1] + ');');
window.__titles = window.__titles || {};
const seen = window.__titles[id] = window.__titles[id] || [];
if (window.__titleTimers && window.__titleTimers[id]) { return; }
window.__titleTimers = window.__titleTimers || {};
window.__titleTimers[id] = setInterval(() => {
    const g = document.querySelector('#' + id + ' .js-plotly-plot');
    if (!g || !g.layout) { return; }
    const t = g.layout.title || {};
    const text = (t.text || '') + (t.subtitle && t.subtitle.text ? ' | ' + t.subtitle.text : '');
    const value = JSON.stringify(extra(g));
    const last = seen[seen.length - 1];
    if (!last || last[0] !== text || last[1] !== value) { seen.push([text, value]); }
}, 25);
"""


def record_titles(driver, graph_id: str, extra: str = "null") -> None:
    """Start the page's record of the figure ``graph_id``'s titles, each with the value of the JavaScript
    expression ``extra`` on the figure ``g`` (:func:`titles_seen`); again after a page load."""
    driver.execute_script(_RECORD_TITLES, graph_id, extra)


def titles_seen(driver, graph_id: str) -> list[tuple[str, object]]:
    """(title, value of the ``extra`` expression) as the figure showed them since :func:`record_titles`, in order."""
    rows = driver.execute_script("return (window.__titles || {})[arguments[0]] || [];", graph_id) or []
    return [(text, json.loads(value)) for text, value in rows]
