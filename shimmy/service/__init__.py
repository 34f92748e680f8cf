"""Service layer: request schemas, the analysis registry, the shared result cache, background
jobs and the HTTP API. Imports the analyses; never imported by them (tests/test_layers.py)."""

from .. import __version__  # noqa: E402,F401  (the package version, for what the UI writes: design files)
