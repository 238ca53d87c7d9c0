"""The HTML report's pages: Markdown the pipeline writes, and its tables, as HTML.

``snakemake --report`` shows an HTML item inline, while a CSV or Markdown item can only be
downloaded; these pages are what it shows.  Each page is one file with no outside
resource, and its style is scoped to ``.casa-page``, so that the same file can also be
included in the report's landing page (workflow/report/workflow.rst).
"""

from __future__ import annotations

import html
import re

import pandas as pd

_STYLE = """<style>
.casa-page { font: 14px/1.45 system-ui, sans-serif; color: #1f2937; }
.casa-page h1 { font-size: 1.4em; margin: 0.6em 0 0.3em; }
.casa-page h2 { font-size: 1.15em; margin: 1.1em 0 0.3em; }
.casa-page h3 { font-size: 1em; margin: 1em 0 0.3em; }
.casa-page table { border-collapse: collapse; margin: 0.4em 0; font-size: 0.9em; }
.casa-page th, .casa-page td { border: 1px solid #d1d5db; padding: 2px 6px; text-align: left;
  vertical-align: top; }
.casa-page th { background: #f3f4f6; position: sticky; top: 0; }
.casa-page td.num { text-align: right; font-variant-numeric: tabular-nums; }
.casa-page .casa-scroll { max-height: 24em; overflow: auto; border: 1px solid #e5e7eb; }
.casa-page .casa-scroll table { margin: 0; }
.casa-page .casa-note { color: #4b5563; }
</style>"""

# Click a header to sort by it, type to filter rows; kept tiny and dependency-free. It
# runs from an image's error handler, not a <script> element: the report embeds its
# landing page in a script, which the text "</script>" would end.
_SORT_AND_FILTER = """
var box = this.parentNode, table = box.querySelector("table");
var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
var input = document.createElement("input");
input.placeholder = "filter rows"; input.style.margin = "0.4em 0";
box.insertBefore(input, box.querySelector(".casa-scroll"));
input.addEventListener("input", function () {
  var q = input.value.toLowerCase();
  rows.forEach(function (r) { r.hidden = r.textContent.toLowerCase().indexOf(q) < 0; });
});
Array.prototype.forEach.call(table.tHead.rows[0].cells, function (th, i) {
  var up = true; th.style.cursor = "pointer"; th.title = "sort";
  th.addEventListener("click", function () {
    rows.sort(function (a, b) {
      var x = a.cells[i].textContent, y = b.cells[i].textContent;
      var nx = parseFloat(x), ny = parseFloat(y);
      var c = (!isNaN(nx) && !isNaN(ny)) ? nx - ny : x.localeCompare(y);
      return up ? c : -c;
    });
    up = !up; rows.forEach(function (r) { body.appendChild(r); });
  });
});
this.onerror = null;
"""
_SCRIPT = (
    '<img src="data:," alt="" hidden onerror="'
    + html.escape(" ".join(_SORT_AND_FILTER.split()), quote=True)
    + '">'
)

_HEADING = re.compile(r"(#{1,3}) (.*)")
_SEPARATOR = re.compile(r"\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?")


def _inline(text: str) -> str:
    """Escaped text with `code` spans."""
    parts = html.escape(text).split("`")
    return "".join(f"<code>{p}</code>" if i % 2 else p for i, p in enumerate(parts))


def _cells(line: str) -> list[str]:
    return [cell.strip() for cell in line.strip().strip("|").split("|")]


def page(body: str, *, title: str) -> str:
    """A self-contained HTML page around ``body``, its style scoped to ``.casa-page``.

    Examples
    --------
    >>> text = page("<p>hi</p>", title="A & B")
    >>> text.startswith("<!DOCTYPE html>"), "<title>A &amp; B</title>" in text
    (True, True)
    """
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{html.escape(title)}</title>\n</head>\n<body>\n{_STYLE}\n"
        f'<div class="casa-page">\n{body}</div>\n</body>\n</html>\n'
    )


def markdown_html(text: str) -> str:
    """The Markdown the pipeline writes (headings, paragraphs, pipe tables) as HTML.

    Only what ``stats.md`` and the results summary use: ``#`` to ``###`` headings,
    paragraphs, pipe tables whose second line is the separator, and `code`; everything
    else is escaped text.

    Examples
    --------
    >>> text = "# Title\\n\\nSome `x` < 1.\\n\\n| A | B |\\n| --- | --- |\\n| 1 | 2 |"
    >>> print(markdown_html(text))
    <h1>Title</h1>
    <p>Some <code>x</code> &lt; 1.</p>
    <table>
    <thead><tr><th>A</th><th>B</th></tr></thead>
    <tbody>
    <tr><td>1</td><td>2</td></tr>
    </tbody>
    </table>
    <BLANKLINE>
    """
    out: list[str] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i].rstrip()
        heading = _HEADING.fullmatch(line)
        if not line:
            i += 1
        elif heading:
            level = len(heading.group(1))
            out.append(f"<h{level}>{_inline(heading.group(2))}</h{level}>")
            i += 1
        elif line.startswith("|") and i + 1 < len(lines) and _SEPARATOR.fullmatch(lines[i + 1]):
            header = "".join(f"<th>{_inline(c)}</th>" for c in _cells(line))
            out += ["<table>", f"<thead><tr>{header}</tr></thead>", "<tbody>"]
            i += 2
            while i < len(lines) and lines[i].startswith("|"):
                cells = "".join(f"<td>{_inline(c)}</td>" for c in _cells(lines[i]))
                out.append(f"<tr>{cells}</tr>")
                i += 1
            out += ["</tbody>", "</table>"]
        else:
            paragraph = []
            while i < len(lines) and lines[i].strip() and not _HEADING.fullmatch(lines[i]):
                if lines[i].startswith("|"):
                    break
                paragraph.append(lines[i].strip())
                i += 1
            out.append(f"<p>{_inline(' '.join(paragraph))}</p>")
    return "\n".join(out) + "\n"


def _cell(value) -> str:
    if isinstance(value, float):
        return "" if pd.isna(value) else f"{value:.6g}"
    return "" if value is None or value is pd.NA else html.escape(str(value))


def table_html(frame: pd.DataFrame, *, title: str, note: str = "") -> str:
    """A table as a browsable HTML fragment: a title, a note, the rows in a scrolling box.

    Numbers keep six significant digits; empty cells stay empty.  In a browser, a filter
    box is added above the rows, and a click on a column's name sorts by it.

    Parameters
    ----------
    frame : pandas.DataFrame
        The table, e.g. ``trials.csv`` read with :func:`casa_core.io.read_table`.
    title : str
        The heading above it.
    note : str
        A sentence under the heading (what the rows are, where the file is).

    Examples
    --------
    >>> frame = pd.DataFrame({"method": ["NA", "CASA"], "error": [0.123456789, float("nan")]})
    >>> text = table_html(frame, title="trials.csv", note="2 rows")
    >>> print(text[text.index("<table>"):text.index("</table>")])
    <table>
    <thead><tr><th>method</th><th>error</th></tr></thead>
    <tbody>
    <tr><td>NA</td><td class="num">0.123457</td></tr>
    <tr><td>CASA</td><td class="num"></td></tr>
    </tbody>
    <BLANKLINE>
    """
    numeric = [pd.api.types.is_numeric_dtype(frame[c]) for c in frame.columns]
    header = "".join(f"<th>{html.escape(str(c))}</th>" for c in frame.columns)
    lines = [f"<h2>{html.escape(title)}</h2>"]
    if note:
        lines.append(f'<p class="casa-note">{html.escape(note)}</p>')
    lines += [
        '<div class="casa-table">',
        _SCRIPT,
        '<div class="casa-scroll">',
        "<table>",
        f"<thead><tr>{header}</tr></thead>",
        "<tbody>",
    ]
    for row in frame.itertuples(index=False):
        cells = "".join(
            f'<td class="num">{_cell(v)}</td>' if num else f"<td>{_cell(v)}</td>"
            for v, num in zip(row, numeric, strict=True)
        )
        lines.append(f"<tr>{cells}</tr>")
    lines += ["</tbody>", "</table>", "</div>", "</div>"]
    return "\n".join(lines) + "\n"
