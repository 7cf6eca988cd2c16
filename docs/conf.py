"""Sphinx configuration of mjtouch's documentation (MyST Markdown pages).

Build: pip install ".[docs]" && sphinx-build -W -b html docs docs/_build/html
"""

import pathlib
import sys

DOCS = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

import mjtouch  # noqa: E402  (the version; autodoc imports it anyway)

project = "mjtouch"
author = "mjtouch developers"
copyright = "mjtouch developers, Apache-2.0"
release = mjtouch.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "mjtouch_docs",
]
source_suffix = {".md": "markdown"}
myst_enable_extensions = ["colon_fence", "dollarmath"]
myst_heading_anchors = 3
exclude_patterns = ["_build"]
root_doc = "index"

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False}
napoleon_google_docstring = False
# Rendering needs no OpenGL: the docs import mjtouch but never draw.
nitpicky = False

html_theme = "furo"
html_title = f"mjtouch {release}"
