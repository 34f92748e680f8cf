"""The workbench: a Dash multi-page app with the HTTP API on the same Flask server.

``gunicorn app:server`` serves both. Pages live in ``pages/``; styling in ``assets/``
(no CDN). Numerics never run here: pages call :mod:`shimmy.service.analyses`, which
validates, caches and computes.
"""

from __future__ import annotations

import os

import diskcache
from dash import Dash, DiskcacheManager

from shimmy.service import settings
from shimmy.service.api import api

background = DiskcacheManager(diskcache.Cache(str(settings.cache_dir() / "dash-background")), expire=3600)

app = Dash(__name__, use_pages=True, title="shimmy workbench", background_callback_manager=background,
           suppress_callback_exceptions=True, update_title=None)
server = app.server
server.config["MAX_CONTENT_LENGTH"] = settings.MAX_BODY_BYTES
server.register_blueprint(api)

from ui import layout  # noqa: E402  (needs the registered pages)

app.layout = layout.shell()

if __name__ == "__main__":
    app.run(host="127.0.0.1", port=int(os.environ.get("PORT", "8050")), debug=False)
