"""MkDocs hook (``hooks:`` in mkdocs.yml): the docstrings' Sphinx roles read as plain code.

The package's numpydoc docstrings name other objects Sphinx's way (``:class:`~handeye.x.Y```), which
mkdocstrings renders literally (``:class:`` before the code). This hook drops the role and, as Sphinx
does for ``~``, keeps only the last part of the dotted name.
"""

from __future__ import annotations

import re

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|data|mod|attr|exc|obj|const):<code>(~?)([^<]+)</code>")


def plain_roles(html: str) -> str:
    """``:class:<code>~a.b.C</code>`` -> ``<code>C</code>``; without ``~`` the whole name is kept."""
    return ROLE.sub(lambda m: f"<code>{m.group(2).rsplit('.', 1)[-1] if m.group(1) else m.group(2)}</code>", html)


def on_page_content(html: str, **_: object) -> str:
    """MkDocs event: every page's HTML, after Markdown and mkdocstrings."""
    return plain_roles(html)
