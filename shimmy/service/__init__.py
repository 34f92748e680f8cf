"""Service layer: request schemas, the analysis registry, the shared result cache, background
jobs, the HTTP API, who may use it, and the proxy in front of it (nginx, ``python -m shimmy serve``). Imports the analyses; never imported by them (tests/test_layers.py)."""

