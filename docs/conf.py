"""Sphinx configuration of shimmy's documentation (build: ``python -m sphinx -W -n -b html docs docs/_build``).

Sphinx rather than mkdocs because the package's docstrings are reStructuredText with Sphinx roles
(``:func:``, ``:class:``, ``:mod:``) and literal blocks: autodoc renders them as written and, in
nitpicky mode (``-n``), every cross-reference in them is checked. The narrative pages are Markdown
(MyST). Tables of parameters, endpoints, request fields, limits and CLI options are generated from
the code by the directives in ``_ext/shimmy_docs.py``.
"""

from __future__ import annotations

import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

import shimmy  # noqa: E402

project = "shimmy"
author = "the shimmy developers"
copyright = "the shimmy developers"
version = release = shimmy.__version__

# sphinx-mathjax-offline ships MathJax into the site, so the equations render without a network.
extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.mathjax", "sphinx-mathjax-offline",
              "sphinx.ext.viewcode", "shimmy_docs"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

html_theme = "furo"
# The API's functions and classes are not entries of the table of contents (its modules' headings are):
# with them, furo copied a tree of ~500 entries into each of the 95 pages (the source pages included),
# half of the build's time.
toc_object_entries = False
html_title = f"shimmy {release}"
html_static_path = ["_static"]
html_css_files = ["shimmy.css"]

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autodoc_default_options = {"members": True, "undoc-members": True, "show-inheritance": True}

# Nitpicky: every reference must resolve, except to other libraries (the offline build loads no
# inventories of theirs) and the quoted annotations autodoc gives dataclass fields of builtin generic
# types (tuple[float, float] arrives as 'tuple[float, split at its comma).
nitpicky = True
EXTERNAL = "np|numpy|scipy|typing|collections|concurrent|distributed|flask|enum|pathlib|os|argparse|subprocess"
nitpick_ignore_regex = [
    (r"py:.*", rf"({EXTERNAL})\..*"),
    (r"py:class", r"'.*"),
]
autodoc_inherit_docstrings = False
