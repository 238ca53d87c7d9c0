"""The HTML report's pages (``casa report``).

The modules, each with one job:

- :mod:`~casa_core.report.pages`: The HTML report's pages: Markdown the pipeline writes, and
  its tables, as HTML.
"""

from casa_core.report.pages import (
    markdown_html,
    page,
    table_html,
)

__all__ = [
    "markdown_html",
    "page",
    "table_html",
]
