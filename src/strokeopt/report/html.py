"""One self-contained HTML page: sections, tables, inline SVG figures, print CSS; the standard library only.

The building blocks of the design report and of the comparison (:mod:`.design_report`,
:mod:`.compare_report`): every figure is inlined as SVG text (no file, no URL, no script), every
number a table shows from a result carries its key and exact value in ``data-key`` /
``data-value`` attributes, so a reader (or a test) can check it against ``strokeopt solve --json``.
"""

from __future__ import annotations

import io
import math
import re
from html import escape

from .format import format_value


def _scalar(value):
    """A numpy scalar as the Python number it is (JSON's view of it)."""
    return value.item() if hasattr(value, "item") and not isinstance(value, (str, bytes)) else value

#: Screen and print: A4 pages (figures are drawn at the printed width, 186 mm); sections follow one another
#: (the inputs, an appendix, start a page); a heading stays with what follows it, a figure with its caption,
#: a table whole (one longer than a page splits between rows).
CSS = """
body { font-family: "DejaVu Sans", Arial, sans-serif; font-size: 10.5pt; color: #222; max-width: 60em;
       margin: 1.5em auto; padding: 0 1em; line-height: 1.35; }
h1 { font-size: 17pt; margin-bottom: 0.2em; } h2 { font-size: 13.5pt; border-bottom: 2px solid #446;
  padding-bottom: 0.15em; margin-top: 1.6em; } h3 { font-size: 11pt; margin-bottom: 0.3em; }
p.sub { color: #555; margin-top: 0; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 9pt; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.5em; text-align: right; vertical-align: top; }
th { background: #eef0f5; } td.text, th.text { text-align: left; }
td.text { overflow-wrap: anywhere; }  /* a long path (a problem file) wraps instead of leaving the page */
td.better { background: #d9f2d9; font-weight: bold; }
.ok { color: #176117; font-weight: bold; } .fail { color: #a61b1b; font-weight: bold; }
table.compare th.text { min-width: 13em; } .keyfacts td { font-size: 10pt; } .keyfacts th { white-space: nowrap; } .keyfacts td.text { max-width: 34em; } figure { margin: 0.5em 0 1em; } figure svg { max-width: 100%; height: auto; }
figcaption { font-size: 9pt; color: #444; } nav ol { columns: 2; font-size: 9.5pt; }
figure, table, tr, figcaption, .keep { break-inside: avoid; page-break-inside: avoid; }
h2, h3 { break-after: avoid; page-break-after: avoid; }
pre { font-size: 8pt; background: #f6f6f6; padding: 0.5em; white-space: pre-wrap; }
.note { font-size: 9pt; color: #444; }
@page { size: A4; margin: 14mm 12mm; }
@media print { body { max-width: none; margin: 0; padding: 0; font-size: 9.5pt; }
  section { break-before: auto; } section#inputs { break-before: page; }
  h2 { margin-top: 1.0em; } nav { display: none; } figure svg { width: 100%; height: auto; } }
"""


def page(title: str, subtitle: str, sections: list[tuple[str, str, str]]) -> str:
    """The whole document: ``sections`` are ``(id, heading, body html)`` in reading order."""
    nav = "<nav><ol>" + "".join(f'<li><a href="#{sid}">{escape(head)}</a></li>' for sid, head, _ in sections) \
          + "</ol></nav>"
    first = ' class="first"'
    body = "".join(f'<section id="{sid}"{first if i == 0 else ""}><h2>{escape(head)}</h2>{html}</section>\n'
                   for i, (sid, head, html) in enumerate(sections))
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{escape(title)}</title>'
            f"<style>{CSS}</style></head>\n<body><h1>{escape(title)}</h1><p class=\"sub\">{escape(subtitle)}</p>"
            f"{nav}\n{body}</body></html>\n")


def _cls(cls: str) -> str:
    return f' class="{cls}"' if cls else ""


def para(text: str, cls: str = "") -> str:
    return f"<p{_cls(cls)}>{escape(text)}</p>"


def heading(text: str) -> str:
    return f"<h3>{escape(text)}</h3>"


def verdict(ok: bool | None, yes: str = "pass", no: str = "FAIL") -> str:
    """A pass/fail word, coloured."""
    if ok is None:
        return "-"
    return f'<span class="ok">{escape(yes)}</span>' if ok else f'<span class="fail">{escape(no)}</span>'


def _attr_value(value) -> str:
    value = _scalar(value)  # numpy scalars as Python's (inf stays: null below)
    if isinstance(value, bool) or value is None:
        return str(value).lower() if value is not None else "null"
    if isinstance(value, float):
        if math.isnan(value):
            raise ValueError("NaN in a report cell: refusing to report it")
        return repr(value) if math.isfinite(value) else "null"  # as in JSON (io/plain.py): unbounded is null
    return str(value)


def cell(value, key: str | None = None, cls: str = "", digits: int = 4, shown: str | None = None) -> str:
    """One table cell: the value formatted like the text tables (``shown``: as given, e.g. an angle of a table's
    grid, 30 not 30.00); ``key``: its ``data-key`` (its place in the ``solve --json`` report) with the exact value
    in ``data-value``."""
    text = shown if shown is not None else value if isinstance(value, str) and not key else format_value(value, digits)
    classes = ([cls] if cls else []) + (["text"] if isinstance(value, str) or value is None else [])
    attrs = f' class="{" ".join(classes)}"' if classes else ""
    if key is not None:
        attrs += f' data-key="{escape(key)}" data-value="{escape(_attr_value(value))}"'
    return f"<td{attrs}>{escape(str(text))}</td>"


def raw_cell(html: str, cls: str = "text") -> str:
    """A table cell holding markup made here (a :func:`verdict`), not a value."""
    return f'<td class="{cls}">{html}</td>'


def _text(html: str) -> str:
    """A cell's text (its markup removed)."""
    from html import unescape

    return unescape(re.sub(r"<[^>]+>", "", html)).strip()


def table(head: list[str], rows: list[list[str]], cls: str = "", keep_empty: bool = False) -> str:
    """A table from header texts and rows of :func:`cell` strings; a column no row has a value in (every
    cell empty or '-') is left out unless ``keep_empty``."""
    if rows and not keep_empty:
        keep = [j for j in range(len(head)) if any(_text(r[j]) not in ("", "-") for r in rows if j < len(r))]
        head = [head[j] for j in keep]
        rows = [[r[j] for j in keep if j < len(r)] for r in rows]
    th = "".join(f"<th>{escape(h)}</th>" for h in head)
    body = "".join("<tr>" + "".join(r) + "</tr>" for r in rows)
    return f"<table{_cls(cls)}><thead><tr>{th}</tr></thead><tbody>{body}</tbody></table>"


def key_table(pairs: list[tuple[str, object, str | None]], cls: str = "keyfacts") -> str:
    """A two-column table of (label, value, data-key) rows; a value None leaves its row out."""
    rows = [[f'<th class="text">{escape(label)}</th>', cell(value, key)] for label, value, key in pairs
            if value is not None]  # a fact the design does not have is not a row
    return f'<table class="{cls}"><tbody>' + "".join("<tr>" + "".join(r) + "</tr>" for r in rows) + "</tbody></table>"


def svg_figure(fig, caption: str = "") -> str:
    """A matplotlib figure as inline SVG (text as text, not paths: small and searchable), then closed."""
    import matplotlib.pyplot as plt

    from .figures import fit_titles

    fit_titles(fig)  # no title wider than its axes: nothing clipped at the figure's edge
    buf = io.StringIO()
    with plt.rc_context({"svg.fonttype": "none", "svg.hashsalt": "strokeopt"}):
        fig.savefig(buf, format="svg")  # constrained layout: no second draw for a tight box
    plt.close(fig)
    svg = buf.getvalue()
    svg = svg[svg.index("<svg"):]  # drop the XML prolog and DOCTYPE: the SVG lives inside the HTML
    svg = re.sub(r"<metadata>.*?</metadata>", "", svg, flags=re.S)
    cap = f"<figcaption>{escape(caption)}</figcaption>" if caption else ""
    return f"<figure>{svg}{cap}</figure>"


def pre(text: str) -> str:
    return f"<pre>{escape(text)}</pre>"
