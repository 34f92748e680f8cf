"""Service layer: request schemas, the analysis registry, the shared result cache, background
jobs and the HTTP API. Imports the analyses; never imported by them (tests/test_layers.py)."""

