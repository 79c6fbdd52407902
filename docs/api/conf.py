# SPDX-License-Identifier: BSD-3-Clause
# Sphinx configuration of the Python API reference (scripts/build-docs.sh): autodoc reads the
# docstrings of the built module (PYTHONPATH=build/python); Debian's python3-sphinx, no theme or
# extension from elsewhere.
import ukdyn

project = "ukdyn"
author = "the ukdyn authors"
copyright = "the ukdyn authors, BSD-3-Clause"
release = version = ukdyn.__version__
extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon"]
autodoc_member_order = "bysource"
# "Attributes:" sections as fields (not a second description of a property of the same name)
napoleon_use_ivar = True
autodoc_typehints = "signature"
autodoc_default_options = {"members": True, "show-inheritance": True}
# the docstrings are plain text with ``code`` in RST's literal markup
default_role = "literal"
html_theme = "alabaster"
html_title = "ukdyn %s: the Python API" % release
master_doc = "index"
exclude_patterns = []
nitpicky = False

# The docstrings are plain text with ``literals`` and :func:`roles` (docs/style.md), not full
# reStructuredText: outside those, a name ending in "_" (lambda_), "|x|" and "*" (not a list's
# bullet) are text, not a link, a substitution or emphasis, and `x` is the literal ``x`` (a
# YAML key in it, `control:`, would end RST's interpreted text early).
import re as _re

_MARKUP = _re.compile(r"(``.+?``|:[a-z:]+:`[^`]+`)")


def _plain_text(app, what, name, obj, options, lines):
    for i, line in enumerate(lines):
        bullet = _re.match(r"\s*\* ", line)
        head, line = (line[:bullet.end()], line[bullet.end():]) if bullet else ("", line)
        parts = _MARKUP.split(line)
        for k in range(0, len(parts), 2):
            text = parts[k].replace("\\", "\\\\").replace("|", "\\|").replace("*", "\\*")
            text = _re.sub(r"(?<=\w)_(?=\W|$)", r"\\_", text)
            parts[k] = _re.sub(r"`([^`]+)`", r"``\1``", text)
        lines[i] = head + "".join(parts)


def setup(app):
    # (before napoleon, whose attribute parsing splits "type: text" at a colon outside ``..``)
    app.connect("autodoc-process-docstring", _plain_text, priority=400)
