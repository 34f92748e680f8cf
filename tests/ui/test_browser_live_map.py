"""The map follows the design: a design one step from a cached map is computed by itself once the
design stands still, the previous map faint until the new one lands; a design with no cached
neighbour waits for Compute and says so. Real Chromium against gunicorn (tests/ui/browser.py)."""

from __future__ import annotations

import time

import pytest

selenium = pytest.importorskip("selenium")
from selenium.webdriver.common.by import By  # noqa: E402

from ui import live  # noqa: E402
from browser import (SHOTS, browser_fixture, by_id, idle, job_records, on_figure, pattern, record_titles,  # noqa: E402
                     severe, text_of, titles_seen, type_into, wait_for)

browser = browser_fixture("chromium-live-map", "1440,900")
PAGE = "/stability-map?shade=nes&fz_min=300&fz_max=900&resolution=4"


def _title(browser) -> str:
    return on_figure(browser, "map-graph", "const t = g.layout.title || {}; return (t.text || '') + "
                                           "(t.subtitle && t.subtitle.text ? ' | ' + t.subtitle.text : '');") or ""


def _seen(browser, text: str) -> bool:
    """Whether the map figure has shown a title with ``text`` since its titles were recorded (or shows one)."""
    return any(text in t for t, _ in titles_seen(browser, "map-graph")) or text in _title(browser)


def _faded(browser) -> bool:
    return bool(on_figure(browser, "map-graph", "return (g.layout.shapes || []).some(s => s.xref === 'paper' "
                                                "&& s.fillcolor && s.fillcolor.indexOf('255,255,255') >= 0);"))


def test_the_map_follows_a_design_step_by_itself(server, browser):
    before = set(job_records(server))
    browser.get(server.base + PAGE + "&e_p=0.0012")
    run = wait_for(lambda: browser.find_elements(By.ID, "map-run"), what="the Compute button")[0]
    idle(browser)
    # the page's record of the titles, each with the shaded regions and the previous map's traces drawn then:
    # a title shown briefly is seen on a loaded machine
    record_titles(browser, "map-graph", "[g.data.filter(t => t.fill === 'toself').length, "
                                        "g.data.filter(t => (t.name || '').indexOf('(previous)') >= 0).length]")
    run.click()
    # the curves are drawn as they are known, before the slices and the shading
    wait_for(lambda: _seen(browser, "Making the map | Hopf curves"), timeout=240, interval=0.1,
             what=lambda: f"the first map's curves before its shading (titles: {titles_seen(browser, 'map-graph')})")
    if "Making the map | Hopf curves" in _title(browser):
        browser.save_screenshot(str(SHOTS / "live-map-sketch-1440.png"))
    wait_for(lambda: "Shimmy type of" in _title(browser), timeout=240, what="the first map")
    titles = titles_seen(browser, "map-graph")
    sketches = [k for k, (t, _) in enumerate(titles) if "Making the map | Hopf curves" in t]
    assert sketches and all(titles[k][1][0] == 0 for k in sketches), titles  # no region shaded while sketched
    assert sketches[0] < next(k for k, (t, _) in enumerate(titles) if "Shimmy type of" in t), titles
    first = [i for i in job_records(server) if i not in before]
    assert len(first) == 1

    # one step of e_p (+10 %): computed by itself, warmed from the cached map, the old map faint meanwhile
    box = wait_for(lambda: by_id(browser, pattern("e_p", "param-box")), what="the e_p box")
    type_into(box, "0.00132")
    wait_for(lambda: _faded(browser) or "New design's map" in _title(browser)
             or "Making the new design's map" in _title(browser), timeout=30,
             interval=0.05, what="the previous map faint while the next is made")
    browser.save_screenshot(str(SHOTS / "live-map-fading-1440.png"))
    # the new design's curves as they come, over the previous map (its regions and curves faint)
    wait_for(lambda: _seen(browser, "Making the new design's map"), timeout=120, interval=0.1,
             what=lambda: "the new design's curves over the previous map (the figure's title: "
             f"{_title(browser)!r}; status: {text_of(browser, 'map-status')!r}; the jobs: "
             + "; ".join(f"{j['analysis']} {j['status']} {j['message']}" for i, j in job_records(server).items()
                         if i not in before and i not in first) + ")")
    # drawn over the previous map's faint regions and curves
    warm_sketches = [extra for t, extra in titles_seen(browser, "map-graph") if "Making the new design's map" in t]
    assert warm_sketches and all(extra[1] > 0 for extra in warm_sketches), warm_sketches
    if "Making the new design's map" in _title(browser):
        browser.save_screenshot(str(SHOTS / "live-map-sketch-warm-1440.png"))
    wait_for(lambda: "Shimmy type of" in _title(browser) and not _faded(browser), timeout=240,
             what="the warmed map")
    second = [j for i, j in job_records(server).items() if i not in before and i not in first]
    assert len(second) == 1 and second[0]["status"] == "done"
    assert second[0]["request"]["params"]["e_p"] == 0.00132
    from shimmy.service import cache

    with server.cache_env():
        result = cache.get("map", second[0]["request"])
    assert result["methods"]["warmed_from"]["changed"] == {"e_p": [0.0012, 0.00132]}
    browser.save_screenshot(str(SHOTS / "live-map-warmed-1440.png"))

    # far away (e_p x 3): nothing starts; the status says the map shown is of the previous design
    count = len(job_records(server))
    type_into(box, "0.004")
    wait_for(lambda: "previous design" in text_of(browser, "map-status"), timeout=30,
             what="the status naming the previous design")
    assert len(job_records(server)) == count
    assert severe(browser) == []


def test_the_overview_boundary_follows_the_design(server, browser):
    """The Hopf-curve boundary (a few tenths of a second per configuration) follows every design the
    panel settles on, with no click: jobs for the configurations whose answer the cache lacks (an
    e_p step leaves original's and pd's models as they were: their answer may be cached already, by
    whatever ran before on this server), then all four drawn."""
    from shimmy.service import cache

    before = set(job_records(server))
    browser.get(server.base + "/?e_p=0.0015")
    wait_for(lambda: browser.find_elements(By.ID, "ov-boundary-graph"), what="the boundary figure")
    idle(browser)
    type_into(wait_for(lambda: by_id(browser, pattern("e_p", "param-box")), what="the e_p box"), "0.0016")

    def boundary_jobs():
        return [j for i, j in job_records(server).items() if i not in before and j["analysis"] == "hopf_curves"]

    def cached(config):
        request = next(j["request"] for j in boundary_jobs() if j["request"]["config"] == "nes")
        with server.cache_env():
            return cache.get("hopf_curves", {**request, "config": config})

    def jobs_now():
        return "the four configurations' Hopf curves of the new design; its jobs: " + "; ".join(
            f"{j['request']['config']} {j['status']} {j['message']} {j['error'] or ''}" for j in boundary_jobs())

    # nes and nes_pd (e_p enters their models) at e_p = 0.0016 were never asked before: computed now
    wait_for(lambda: {"nes", "nes_pd"} <= {j["request"]["config"] for j in boundary_jobs()}
             and all(j["status"] == "done" for j in boundary_jobs()), timeout=120, what=jobs_now)
    assert {j["request"]["params"]["e_p"] for j in boundary_jobs()} == {0.0016}
    assert all(cached(config) is not None for config in ("original", "nes", "pd", "nes_pd"))
    wait_for(lambda: on_figure(browser, "ov-boundary-graph", "return g.layout.title.text;") ==
             "Hopf curves of straight rolling", timeout=60, what="the new boundary drawn")
    assert on_figure(browser, "ov-boundary-graph", "return g.data.length;") >= 4
    assert severe(browser) == []


def test_a_held_slider_starts_nothing_until_it_is_let_go(server, browser):
    """The boundary follows the design once it stands still: a slider dragged and held (longer than
    the arrow keys' quiet time) starts no job; at its release the design it was let go at is computed,
    and no design it passed on the way. (The linear growth plot follows the drag meanwhile.)"""
    from selenium.webdriver.common.action_chains import ActionChains

    browser.get(server.base + "/?e_p=0.00105")
    wait_for(lambda: browser.find_elements(By.ID, "ov-boundary-graph"), what="the boundary figure")
    idle(browser)
    before = set(job_records(server))
    # dcc.Slider's code is loaded lazily (a chunk of its own): under load the slider is drawn after the figures
    slider = wait_for(lambda: by_id(browser, pattern("e_p", "param")), what="the e_p slider")
    handle = slider.find_element(By.CSS_SELECTOR, "[role='slider']")
    width = slider.size["width"]
    drag = ActionChains(browser).click_and_hold(handle)
    for _ in range(3):
        drag = drag.move_by_offset(width // 30, 0).pause(0.2)
    drag.perform()

    def dragged():  # the slider's value once the address carries it (the design the panel holds)
        value = float(handle.get_attribute("aria-valuenow"))
        return value if f"e_p={value:g}" in browser.current_url else None

    held = wait_for(dragged, timeout=30, what=lambda: f"the dragged value in the address ({browser.current_url}, "
                    f"slider at {handle.get_attribute('aria-valuenow')})")
    assert held > 0.00105
    time.sleep(3 * live.SETTLE_MS / 1000)  # held still, longer than the keys' quiet time
    new = [(j["analysis"], j["request"].get("config"), j["request"]["params"]["e_p"])
           for i, j in job_records(server).items() if i not in before]
    assert new == [], f"jobs started while the slider was held: {new}"
    ActionChains(browser).release().perform()

    def boundary_jobs():
        return [j for i, j in job_records(server).items() if i not in before and j["analysis"] == "hopf_curves"]

    wait_for(lambda: {"nes", "nes_pd"} <= {j["request"]["config"] for j in boundary_jobs()}, timeout=60,
             what="the boundary's jobs at the release")
    assert {j["request"]["params"]["e_p"] for j in boundary_jobs()} == {held}
    assert severe(browser) == []
