"""Sphinx configuration of andyc's documentation site (make docs; issue 45).

The reference pages are generated here, before Sphinx reads the sources (docs/_ext/andyc_reference.py), from the
JSON Schemas, the click commands, the status tables and the shipped models: they are never committed.
"""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path[:0] = [str(DOCS.parent), str(DOCS / "_ext")]

import andyc_reference  # noqa: E402  (found through the path above)

andyc_reference.write_all(DOCS)

project = "andyc"
author = "andyc's authors"
extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# the closing notes' screenshots and the benchmark data are documents' attachments, not pages
exclude_patterns = ["_build", "bench/**", "_ext/**"]
myst_heading_anchors = 3
napoleon_numpy_docstring = True
napoleon_google_docstring = False
autodoc_member_order = "bysource"
html_theme = "alabaster"
html_title = "andyc"
smartquotes = False         # (a command's help text writes options as --name: Sphinx's smart quotes made them en dashes)
# Every cross-reference must resolve (a broken link fails the build), except these internal classes that the
# public functions' signatures name but that the reference does not document (yet).
nitpicky = True
nitpick_ignore = [("py:class", name) for name in (
    "andyc.spec.model.Spec", "andyc.symbolic.model.SymbolicModel", "andyc.codegen.buildfiles.BuildResult",
    "andyc.runtime.compiled.CompiledModel", "andyc.runtime.interrupts.Interrupts")]
