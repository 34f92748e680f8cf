"""Who may use the service: every request is checked, but ``GET /api/v1/health``.

``SHIMMY_AUTH`` (``shimmy.service.settings.auth_mode``): ``none``, the default while the server
listens on loopback only, lets every request in as one anonymous user with every right; ``token``,
the default (and the only choice, unless ``SHIMMY_ALLOW_ANONYMOUS=1``) when it listens beyond
loopback, asks each request for a credential:

* ``Authorization: Bearer TOKEN``: an API token (:mod:`shimmy.service.tokens`), for scripts;
* the ``shimmy_session`` cookie, for the workbench: set by the sign-in page (``/login``), where a
  user pastes a token of scope compute or admin. The cookie names the token by its id, with an
  expiry, signed (HMAC-SHA256) with a key kept beside the tokens; it is HttpOnly, SameSite=Lax and
  Secure when the page came over https (or ``SHIMMY_COOKIE_SECURE=1``). Revoking the token ends its
  sessions at their next request.

A request without a credential, or with a wrong, expired or revoked one, is answered 401 with the
same words whatever was wrong (API and callbacks: JSON naming ``Authorization``; a page: a redirect
to the sign-in page); a credential whose scope does not allow the request, 403. Tokens never reach a
log: they are accepted only in the header, the cookie (which carries no token) and the sign-in
form's body, never in an address. Sign-in attempts are limited per client address
(:func:`shimmy.service.admission.take_login_attempt`): the connection's, or behind the proxy the one it
forwards (:mod:`shimmy.service.forwarded`).
"""

from __future__ import annotations

import base64
import functools
import hashlib
import hmac
import html
import logging
import os
import secrets
import time
import urllib.parse
from dataclasses import dataclass

import flask

from . import admission, settings, tokens

log = logging.getLogger(__name__)

COOKIE = "shimmy_session"
LOGIN_PATH = "/login"
LOGOUT_PATH = "/logout"
#: The one answer to a missing or bad credential (no hint of which part was wrong).
UNAUTHORISED = "authentication required: send Authorization: Bearer TOKEN with a valid token (or sign in)"
RANK = {scope: k for k, scope in enumerate(tokens.SCOPES)}


@dataclass(frozen=True)
class Principal:
    """Who is asking: a user with a scope (never the token itself)."""

    user: str
    scope: str
    token_id: str | None = None
    via: str = "anonymous"  # token | session | anonymous

    @property
    def identified(self) -> bool:
        return self.via != "anonymous"

    def allows(self, scope: str) -> bool:
        return RANK[self.scope] >= RANK[scope]


#: Everyone, when the server does not check (SHIMMY_AUTH=none): one user with every right.
ANONYMOUS = Principal("anonymous", "admin")
#: A request the server checks but did not authorise (health, the sign-in page): the least right.
NOBODY = Principal("nobody", "read", None, "unchecked")


def enabled() -> bool:
    """Whether requests need a credential (SHIMMY_AUTH resolved once per set of environment values)."""
    return _mode(os.environ.get("SHIMMY_AUTH"), os.environ.get("SHIMMY_LISTEN"),
                 os.environ.get("SHIMMY_PROXY_LISTEN"), os.environ.get("SHIMMY_ALLOW_ANONYMOUS")) == "token"


@functools.lru_cache(maxsize=8)
def _mode(*_environment) -> str:
    return settings.auth_mode()


def current() -> Principal:
    """The principal of the request being served: ANONYMOUS outside a request or with auth off, NOBODY for a
    request that was not authorised (health, the sign-in page)."""
    if not flask.has_request_context():
        return ANONYMOUS
    return flask.g.get("principal") or (NOBODY if enabled() else ANONYMOUS)


# -- credentials ------------------------------------------------------------------------------------


def identify(req: flask.Request) -> Principal | None:
    """The principal of ``req``'s credential, or None when it has none or a bad one. A request that sends
    an Authorization header is judged by it alone (a bad one never falls back to a cookie)."""
    if not enabled():
        return ANONYMOUS
    header = req.headers.get("Authorization")
    if header is not None:
        scheme, _, secret = header.strip().partition(" ")
        if scheme.lower() != "bearer":
            return None
        token = tokens.verify(secret.strip())
        return None if token is None else Principal(token.user, token.scope, token.id, "token")
    cookie = req.cookies.get(COOKIE)
    return None if not cookie else session_principal(cookie)


def _b64(raw: bytes) -> str:
    return base64.urlsafe_b64encode(raw).rstrip(b"=").decode()


def _sign(payload: str) -> str:
    return _b64(hmac.new(tokens.session_key(), payload.encode(), hashlib.sha256).digest())


def session_cookie(token: tokens.Token, now: float | None = None) -> tuple[str, int]:
    """(the cookie's value, its lifetime in seconds) for a session signed in with ``token``."""
    lifetime = int(settings.SESSION_HOURS * 3600)
    payload = f"{token.id}.{int((now or time.time()) + lifetime)}.{secrets.token_hex(8)}"
    return f"{payload}.{_sign(payload)}", lifetime


def session_principal(cookie: str) -> Principal | None:
    """The principal of a session cookie: its signature right, not expired, its token not revoked."""
    if len(cookie) > 256:
        return None
    parts = cookie.split(".")
    if len(parts) != 4 or not (parts[1].isascii() and parts[1].isdigit()):
        return None
    payload = ".".join(parts[:3])
    if not hmac.compare_digest(_sign(payload).encode(), parts[3].encode("utf-8", "replace")):
        return None
    if int(parts[1]) < time.time():
        return None
    token = tokens.by_id(parts[0])
    return None if token is None else Principal(token.user, token.scope, token.id, "session")


# -- checking requests ------------------------------------------------------------------------------


def authorise(req: flask.Request, scope: str) -> Principal | tuple[int, str]:
    """The request's principal if it may do what needs ``scope`` (kept on ``flask.g.principal``), else
    (401 or 403, the message)."""
    principal = identify(req)
    if principal is None:
        return 401, UNAUTHORISED
    flask.g.principal = principal
    if not principal.allows(scope):
        return 403, (f"the scope of this Authorization ({principal.scope}) does not allow {req.method} {req.path}; "
                     f"it needs {scope}")
    return principal


def challenge_headers() -> dict[str, str]:
    return {"WWW-Authenticate": 'Bearer realm="shimmy"', "Cache-Control": "no-store"}


def install(server: flask.Flask, api_prefix: str) -> None:
    """Check every request to ``server`` outside ``api_prefix`` (the API checks its own): a page or a
    workbench request needs scope compute; without a credential a browser asking for a page is sent to
    the sign-in page, anything else answered 401. Adds the sign-in and sign-out routes."""

    @server.before_request
    def _check():
        path = flask.request.path
        if path.startswith(api_prefix + "/") or path in (LOGIN_PATH, LOGOUT_PATH) or not enabled():
            return None
        outcome = authorise(flask.request, "compute")
        if isinstance(outcome, Principal):
            return None
        status, message = outcome
        if status == 401 and flask.request.method == "GET" and "text/html" in flask.request.headers.get("Accept", ""):
            target = flask.request.full_path.rstrip("?")
            return flask.redirect(f"{LOGIN_PATH}?next={urllib.parse.quote(target, safe='')}", 303)
        return refusal(status, message)

    server.add_url_rule(LOGIN_PATH, "shimmy_login", _login, methods=["GET", "POST"])
    server.add_url_rule(LOGOUT_PATH, "shimmy_logout", _logout, methods=["POST"])


def refusal(status: int, message: str) -> flask.Response:
    import json

    body = json.dumps({"error": message, "field": "Authorization", "allowed": "Authorization: Bearer TOKEN "
                       "(a token of the right scope), or a signed-in session"})
    return flask.Response(body, status, mimetype="application/json",
                          headers=challenge_headers() if status == 401 else {"Cache-Control": "no-store"})


def _next_path(value: str | None) -> str:
    """Where to go after signing in: a path of this server only (never another site)."""
    if not value or not value.startswith("/") or value.startswith("//") or "\\" in value or any(
            ord(c) < 32 for c in value):
        return "/"
    return value


def _client() -> str:
    return flask.request.remote_addr or "unknown"


def _login():
    if not enabled():
        return flask.redirect("/", 303)
    req = flask.request
    target = _next_path(req.values.get("next"))
    if req.method == "GET":
        return _page(target)
    if req.headers.get("Sec-Fetch-Site") == "cross-site":  # another site's form signing someone in
        return _page(target, "Sign-in from another site refused.", 403)
    try:
        admission.take_login_attempt(_client())
    except admission.Busy as busy:
        return _page(target, str(busy), 429, busy.headers())
    token = tokens.verify(req.form.get("token", "").strip())
    if token is None:
        log.info("sign-in refused from %s", _client())
        return _page(target, "That token was not accepted.", 401, challenge_headers())
    if RANK[token.scope] < RANK["compute"]:
        return _page(target, f"A token of scope {token.scope} cannot use the workbench; it needs compute or admin.",
                     403)
    value, lifetime = session_cookie(token)
    secure = settings.cookie_secure()
    response = flask.redirect(target, 303)
    response.set_cookie(COOKIE, value, max_age=lifetime, httponly=True, samesite="Lax", path="/",
                        secure=req.scheme == "https" if secure is None else secure)
    log.info("user %s signed in (token %s)", token.user, token.id)
    return response


def _logout():
    response = flask.redirect(LOGIN_PATH, 303)
    response.delete_cookie(COOKIE, path="/", httponly=True, samesite="Lax")
    return response


def _page(target: str, problem: str | None = None, status: int = 200,
          headers: dict[str, str] | None = None) -> flask.Response:
    notice = f'<p class="error" role="alert">{html.escape(problem)}</p>' if problem else ""
    body = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>Sign in · shimmy workbench</title>
<style>body{{font-family:system-ui,sans-serif;max-width:28rem;margin:4rem auto;padding:0 1rem;color:#222}}
label{{display:block;margin:1rem 0 .3rem}}input{{width:100%;padding:.5rem;font:inherit;box-sizing:border-box}}
button{{margin-top:1rem;padding:.5rem 1.2rem;font:inherit}}.error{{color:#b00020}}.hint{{color:#555}}</style>
</head><body><h1>shimmy workbench</h1>
<p class="hint">Sign in with an API token of scope compute or admin (an administrator creates one with
<code>python -m shimmy tokens create --user NAME --scope compute</code>).</p>{notice}
<form method="post" action="{LOGIN_PATH}" autocomplete="off">
<input type="hidden" name="next" value="{html.escape(target)}">
<label for="token">Token</label><input id="token" name="token" type="password" required autofocus
 spellcheck="false" autocomplete="off"><button type="submit">Sign in</button></form></body></html>"""
    return flask.Response(body, status, mimetype="text/html", headers={"Cache-Control": "no-store", **(headers or {})})
