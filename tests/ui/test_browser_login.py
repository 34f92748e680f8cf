"""Signing in to the workbench (SHIMMY_AUTH=token), in real headless Chromium against gunicorn: a page
asked for without a session goes to the sign-in page and, once a token is accepted, back to where it
was asked for, with working callbacks; the session cookie is out of the page's scripts' reach; a
session that ends while a page is open sends the page to the sign-in page; signing out ends it."""

from __future__ import annotations

import os
import urllib.parse

import pytest

pytest.importorskip("selenium")
from selenium.webdriver.common.by import By  # noqa: E402
from browser import SHOTS, browser_fixture, idle, trace_count, wait_for  # noqa: E402

from conftest import start_server, stop_server  # noqa: E402

browser = browser_fixture("chromium-profile-login", "1280,900")


@pytest.fixture(scope="module")
def guarded(tmp_path_factory):
    from shimmy.service import tokens

    cache_dir = tmp_path_factory.mktemp("login")
    before = os.environ.get("SHIMMY_CACHE_DIR")
    os.environ["SHIMMY_CACHE_DIR"] = str(cache_dir)
    try:
        _, secret = tokens.create("alice", "compute")
    finally:
        os.environ["SHIMMY_CACHE_DIR"] = before or ""
        if before is None:
            del os.environ["SHIMMY_CACHE_DIR"]
    server = start_server(cache_dir, {"SHIMMY_AUTH": "token"})
    server.secret = secret
    yield server
    stop_server(server)


def _sign_in(driver, token: str) -> None:
    box = wait_for(lambda: driver.find_elements(By.ID, "token"), what="the token box")[0]
    box.clear()
    box.send_keys(token)
    driver.find_element(By.CSS_SELECTOR, "button[type=submit]").click()


def test_sign_in_brings_the_page_asked_for_with_working_callbacks_and_sign_out_ends_it(guarded, browser):
    browser.delete_all_cookies()
    browser.get(guarded.base + "/devices?e_p=0.002")
    wait_for(lambda: "/login" in browser.current_url, what="the sign-in page")
    assert urllib.parse.parse_qs(urllib.parse.urlsplit(browser.current_url).query)["next"] == ["/devices?e_p=0.002"]
    _sign_in(browser, "shm_" + "Z" * 43)
    wait_for(lambda: "not accepted" in browser.page_source, what="the refusal")
    _sign_in(browser, guarded.secret)
    wait_for(lambda: browser.current_url.endswith("/devices?e_p=0.002"), what="the page asked for")
    wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, ".page-header h1"), what="the page header")
    idle(browser)
    wait_for(lambda: trace_count(browser, "dev-torque") >= 2, what="the torque figure (its callback ran)")
    browser.save_screenshot(str(SHOTS / "signed-in-devices.png"))
    cookie = browser.get_cookie("shimmy_session")
    assert cookie["httpOnly"] and cookie["sameSite"] == "Lax" and not cookie["secure"]
    assert "shimmy_session" not in browser.execute_script("return document.cookie")
    assert guarded.secret not in cookie["value"]
    # The session ends while the page is open (here: its cookie goes): the page's next request goes to sign-in.
    browser.delete_cookie("shimmy_session")
    browser.execute_script("fetch('/_dash-update-component', {method: 'POST', headers: {'Content-Type': "
                           "'application/json'}, body: '{}'})")
    wait_for(lambda: "/login" in browser.current_url, what="the sign-in page after the session ended")
    _sign_in(browser, guarded.secret)
    wait_for(lambda: "/devices" in browser.current_url, what="the page again")
    sign_out = wait_for(lambda: browser.find_elements(By.CSS_SELECTOR, ".nav-signout"), what="sign out")[0]
    sign_out.click()
    wait_for(lambda: "/login" in browser.current_url, what="the sign-in page after signing out")
    assert browser.get_cookie("shimmy_session") is None
    browser.get(guarded.base + "/")
    wait_for(lambda: "/login" in browser.current_url, what="sign-in again")
