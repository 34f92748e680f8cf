"""The workbench: a Dash multi-page app with the HTTP API on the same Flask server.

``python -m shimmy serve`` serves both: gunicorn (``app:server``; gunicorn.conf.py beside this file is read by
default) behind nginx, which holds slow clients (shimmy.service.nginx); ``gunicorn app:server`` alone serves
one user on loopback. Pages live in ``pages/``; styling in ``assets/`` (no CDN). Numerics never run here: pages
call :mod:`shimmy.service.analyses` for quick answers and submit long ones as jobs through
:mod:`shimmy.service.jobs` (the API's admission control); Dash starts no process of its own.
"""

from __future__ import annotations

import logging
import os

from dash import Dash

from shimmy.service import auth, forwarded, settings, tokens
from shimmy.service.api import PREFIX, api

settings.cache_dir()  # refuse to start on a cache directory that is not private to this user
# refuse to start with SHIMMY_AUTH=none beyond loopback (unless SHIMMY_ALLOW_ANONYMOUS=1), or oidc (not built)
if settings.auth_mode() == "token" and not tokens.listed():
    logging.getLogger(__name__).warning("SHIMMY_AUTH=token and no API token yet: every request but health is "
                                        "refused; create one with python -m shimmy tokens create --user NAME "
                                        "--scope admin")


class Workbench(Dash):
    def _config(self):
        """The page's config without the Python version Dash puts there (it tells an attacker too much)."""
        config = super()._config()
        config.pop("python_version", None)
        return config


# compress: responses (the 6.3 MB of component bundles, figures' JSON) sent zstd, brotli or gzip to a
# browser that accepts it (flask-compress, through Dash's own option)
app = Workbench(__name__, use_pages=True, title="shimmy workbench", suppress_callback_exceptions=True,
                update_title=None, compress=True)
server = app.server
server.config["MAX_CONTENT_LENGTH"] = settings.MAX_BODY_BYTES
# behind the proxy (python -m shimmy serve): the client's address from its X-Forwarded-For, believed from that
# proxy only (SHIMMY_TRUSTED_PROXY), so that sign-in attempts count per client, not per proxy
server.wsgi_app = forwarded.from_trusted_proxy(server.wsgi_app)
server.register_blueprint(api)
auth.install(server, PREFIX)  # before the callback guard: who may ask is checked before what is asked

from ui import guard, jobs, layout  # noqa: E402  (needs the registered pages)

app.layout = layout.shell()
guard.install(app)
jobs.install(app)

# Dash sets itself up on a worker's first request (copying the registered callbacks into its map);
# two first requests on a threaded worker raced there ("dictionary changed size during iteration",
# a 500 for a page's scripts or layout). Done once here, at import, before any request: that set-up,
# then every before-request hook on a request of the API's health path (no sign-in, no callback check),
# among them dash pages' router, which registers the page-routing callback and the document.title
# clientside script (served meanwhile, a page lacked that script and a callback of it was refused).
with server.test_request_context("/"):
    app._setup_server()
with server.test_request_context(PREFIX + "/health"):
    server.preprocess_request()

if __name__ == "__main__":
    app.run(host="127.0.0.1", port=int(os.environ.get("PORT", "8050")), debug=False)
