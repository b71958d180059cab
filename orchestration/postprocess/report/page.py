"""One self-contained HTML page: plotly.js inlined once, every figure's data inside, a few
lines of our own JavaScript (figures drawn as they are opened, tables sorted by a click on
a column's header).  Opened from disk, offline: nothing is fetched, no server.

A :class:`Page` is a list of sections of HTML; :meth:`Page.figure` adds a plotly figure
(its JSON in a ``<script type="application/json">``, drawn when its section is open: the
sections of every output start closed, so a page of a hundred plots opens at once),
:meth:`Page.table` a table (sortable: its rows as JSON, built by the script).  When every
figure of the open sections is drawn, ``<body>`` gets ``data-drawn="N"`` (the tests wait
for it) and any figure that failed is listed in ``data-failed``.
"""

from __future__ import annotations

import html
import json
import math
import numbers

import numpy as np

from .figures import to_json

#: our page's style: readable on a laptop, printable
STYLE = """
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", sans-serif; margin: 0 auto;
       max-width: 1250px; padding: 0 24px 48px; color: #1d2433; }
h1 { font-size: 22px; margin: 22px 0 2px; } h2 { font-size: 18px; margin: 28px 0 8px;
  border-bottom: 1px solid #d8dde6; padding-bottom: 3px; } h3 { font-size: 15px; }
.sub { color: #5a6478; margin: 0 0 10px; } code { font-size: 12px; }
table { border-collapse: collapse; margin: 6px 0 12px; font-size: 13px; }
th, td { border-bottom: 1px solid #e3e7ee; padding: 3px 9px; text-align: left;
         vertical-align: top; }
th { background: #f3f5f9; position: sticky; top: 0; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.sortable th { cursor: pointer; user-select: none; }
table.sortable th[data-order="asc"]::after { content: " ▲"; }
table.sortable th[data-order="desc"]::after { content: " ▼"; }
.scroll { max-height: 560px; overflow: auto; border: 1px solid #e3e7ee; }
.verdict { display: inline-block; padding: 0 7px; border-radius: 9px; font-size: 12px;
           white-space: nowrap; background: #e9ecf2; color: #394150; }
.verdict.met, .verdict.ok, .verdict.complete { background: #dcf3e3; color: #17612f; }
.verdict.not-met, .verdict.failed, .verdict.error, .verdict.lost
  { background: #fbe0e0; color: #8f1d1d; }
.verdict.undecided { background: #fdf0d5; color: #7a4e00; }
details { margin: 6px 0; } summary { cursor: pointer; font-weight: 600; padding: 4px 0; }
.figure { width: 100%; } .note { color: #5a6478; font-size: 12.5px; }
dl.facts { display: grid; grid-template-columns: max-content auto; gap: 1px 14px;
           margin: 6px 0; font-size: 13px; } dl.facts dt { color: #5a6478; }
nav a { margin-right: 14px; }
"""

#: our page's script: draw the figures of open sections, sort tables
SCRIPT = """
(function () {
  const failed = [];
  let drawn = 0;
  function draw(div) {
    if (div.dataset.state) return Promise.resolve();
    div.dataset.state = "drawing";
    const spec = JSON.parse(document.getElementById(div.dataset.figure).textContent);
    const config = Object.assign({responsive: true, displaylogo: false}, spec.config || {});
    return Plotly.newPlot(div, {data: spec.data, layout: spec.layout, frames: spec.frames,
                                config: config})
      .then(() => { div.dataset.state = "drawn"; drawn += 1; })
      .catch((e) => { div.dataset.state = "failed"; failed.push(div.dataset.figure + ": " + e);
                      console.error(e); });
  }
  function drawOpen(root) {
    const divs = Array.from(root.querySelectorAll("div.figure"))
      .filter((d) => !d.closest("details:not([open])"));
    return divs.reduce((p, d) => p.then(() => draw(d)), Promise.resolve());
  }
  function cell(value) {
    if (value === null) return "";
    if (typeof value !== "number" || Number.isInteger(value)) return String(value);
    return String(Number(value.toPrecision(6)));
  }
  function buildTable(table) {
    const spec = JSON.parse(document.getElementById(table.dataset.table).textContent);
    const head = table.createTHead().insertRow();
    spec.columns.forEach((name, j) => {
      const th = document.createElement("th");
      th.textContent = name;
      if (spec.titles) th.title = spec.titles[j] || "";
      th.addEventListener("click", () => sortBy(table, spec, j, th));
      head.appendChild(th);
    });
    table._rows = spec.rows;
    fill(table, spec);
  }
  function fill(table, spec) {
    const old = table.tBodies[0];
    const body = document.createElement("tbody");
    for (const row of table._rows) {
      const tr = body.insertRow();
      row.forEach((value, j) => {
        const td = tr.insertCell();
        td.textContent = cell(value);
        if (typeof value === "number") td.className = "num";
        if (spec.verdicts && spec.verdicts.includes(j) && value) {
          td.innerHTML = '<span class="verdict ' + value.replace(/ /g, "-") + '">' + value
            + "</span>";
        }
      });
    }
    old ? table.replaceChild(body, old) : table.appendChild(body);
  }
  function sortBy(table, spec, j, th) {
    const order = th.dataset.order === "asc" ? "desc" : "asc";
    table.querySelectorAll("th").forEach((h) => delete h.dataset.order);
    th.dataset.order = order;
    const sign = order === "asc" ? 1 : -1;
    table._rows.sort((a, b) => {
      const x = a[j], y = b[j];
      if (x === null || x === "") return 1;
      if (y === null || y === "") return -1;
      return sign * (typeof x === "number" ? x - y : String(x).localeCompare(String(y)));
    });
    fill(table, spec);
  }
  document.addEventListener("DOMContentLoaded", () => {
    document.querySelectorAll("table[data-table]").forEach(buildTable);
    document.querySelectorAll("details").forEach((d) =>
      d.addEventListener("toggle", () => { if (d.open) drawOpen(d); }));
    drawOpen(document).then(() => {
      document.body.dataset.failed = failed.join("\\n");
      document.body.dataset.drawn = String(drawn);
    });
  });
})();
"""


class Page:
    """A page being written: ``add`` HTML, ``figure`` a plotly figure, ``table`` a table;
    :meth:`html` the whole page."""

    def __init__(self, title: str, subtitle: str = ""):
        self.title, self.subtitle = title, subtitle
        self.parts: list[str] = []
        self._ids = 0

    def _id(self, kind: str) -> str:
        self._ids += 1
        return f"{kind}-{self._ids}"

    def add(self, text: str) -> None:
        self.parts.append(text)

    def heading(self, text: str, anchor: str | None = None) -> None:
        self.add(f'<h2 id="{anchor or ""}">{esc(text)}</h2>' if anchor else f"<h2>{esc(text)}</h2>")

    def note(self, text: str) -> None:
        self.add(f'<p class="note">{esc(text)}</p>')

    def figure(self, figure: dict) -> None:
        """A plotly figure (a dict, :mod:`.figures`; with its frames), drawn when its
        section is open."""
        ident = self._id("figure")
        text = to_json(figure)
        self.add(f'<script type="application/json" id="{ident}">{_script_safe(text)}</script>')
        height = int(figure["layout"].get("height", 400))
        self.add(f'<div class="figure" data-figure="{ident}" style="height:{height}px"></div>')

    def table(self, columns, rows, titles=None, verdicts=()) -> None:
        """A sortable table: ``rows`` of values (numbers, text, None for none); ``titles``
        the columns' tooltips; ``verdicts`` the indices of columns shown as verdicts."""
        ident = self._id("table")
        spec = {
            "columns": list(columns),
            "rows": [[_json_value(v) for v in row] for row in rows],
            "titles": list(titles) if titles else None,
            "verdicts": list(verdicts),
        }
        text = json.dumps(spec, ensure_ascii=False, separators=(",", ":"))
        self.add(f'<script type="application/json" id="{ident}">{_script_safe(text)}</script>')
        self.add(f'<div class="scroll"><table class="sortable" data-table="{ident}"></table></div>')

    def html(self) -> str:
        from plotly.offline import get_plotlyjs

        head = (
            '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{esc(self.title)}</title><style>{STYLE}</style>"
            f"<script>{get_plotlyjs()}</script></head>\n<body>"
            f"<h1>{esc(self.title)}</h1>"
            + (f'<p class="sub">{esc(self.subtitle)}</p>' if self.subtitle else "")
        )
        return head + "\n".join(self.parts) + f"<script>{SCRIPT}</script></body></html>\n"


def esc(text) -> str:
    return html.escape(str(text), quote=True)


def verdict(text: str | None) -> str:
    """A verdict (met, not met, not evaluated, ...) or a status as a coloured badge."""
    if not text:
        return ""
    return f'<span class="verdict {esc(text.replace(" ", "-"))}">{esc(text)}</span>'


def facts(pairs) -> str:
    """A definition list of (label, value) pairs (values HTML-escaped; None left out)."""
    rows = "".join(f"<dt>{esc(k)}</dt><dd>{esc(v)}</dd>" for k, v in pairs if v is not None)
    return f'<dl class="facts">{rows}</dl>'


def static_table(columns, rows, numeric=()) -> str:
    """A small table of HTML cells (already escaped), not sortable; ``numeric``: the
    indices of right-aligned columns."""
    head = "".join(f"<th>{esc(c)}</th>" for c in columns)
    body = "".join(
        "<tr>"
        + "".join(
            f'<td class="num">{c}</td>' if j in numeric else f"<td>{c}</td>"
            for j, c in enumerate(row)
        )
        + "</tr>"
        for row in rows
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _script_safe(text: str) -> str:
    """JSON inside a <script> element: no '</' that would end it early."""
    return text.replace("</", "<\\/")


def _json_value(value):
    """A table cell as JSON: finite numbers as numbers (NumPy's too), NaN and None as
    null, Booleans as true/false text, anything else as text."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value) if math.isfinite(value) else None
    return str(value)
