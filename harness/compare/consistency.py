"""One number per question: every place a written comparison shows a quantity shows the
same value as its record in ``metrics.json``.

:func:`disagreements` reads what ``caustics compare`` wrote (each comparison's
``metrics.json``, its page, its CSV tables, and the index) and lists every place where
two numbers that name the same quantity differ:

* **same pixels**: every method of a scene is scored over the same region, so each
  (view, region)'s ``pixels`` is equal across the scene's methods;
* **the page's Metrics tables**: each record's excess, interval ends, raw value and
  pixels as the page prints them (``reports.build``'s 4 significant digits);
* **the index**: each key metric's excess, interval and raw value in its cell;
* **the cost table**: its scene-settings row's excess relMSE and interval are the
  ``receiver0 / caustic / relmse`` record's;
* **the convergence table**: the row of the scene's own estimator, safeguard and
  iteration count has the record's excess relMSE;
* **the paper's claims**: the one-iteration claim's excesses after 1 and N iterations
  are the convergence table's rows of the plain modified estimator;
* **the checks**: a method target on relMSE quotes the record's excess and interval.

A comparison that failed (its index row says so) has a failure page and no tables: it
is left out. A number ``metrics.json`` holds as ``null`` (strict JSON has no NaN or
infinity) matches any non-finite text on a page.

Numbers computed by the same code on the same maps agree to the last bit; the
tolerance :data:`RELATIVE_TOLERANCE` only absorbs a CSV's text round trip.
"""

from __future__ import annotations

import csv
import json
import math
import re
from html.parser import HTMLParser
from pathlib import Path

from reports.build import page_number

__all__ = ["RELATIVE_TOLERANCE", "disagreements"]

#: Relative difference two written copies of one float may have (``repr`` round trips
#: exactly; 1e-12 leaves room for a reader that parses a shorter form).
RELATIVE_TOLERANCE = 1e-12


class _Tables(HTMLParser):
    """Every ``<table>`` of a page as (caption, header cells, rows of cell texts)."""

    def __init__(self):
        super().__init__()
        self.tables: list[dict] = []
        self._cell: list[str] | None = None
        self._row: list[str] | None = None
        self._in_caption = False

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append({"caption": "", "header": [], "rows": [],
                                "class": dict(attrs).get("class") or ""})
        elif tag == "caption":
            self._in_caption = True
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "br" and self._cell is not None:
            self._cell.append(" ")

    def handle_endtag(self, tag):
        if tag == "caption":
            self._in_caption = False
        elif tag in ("td", "th") and self._cell is not None and self._row is not None:
            self._row.append(" ".join("".join(self._cell).split()))
            self._cell = None
        elif tag == "tr" and self._row is not None and self.tables:
            table = self.tables[-1]
            if not table["header"]:
                table["header"] = self._row
            else:
                table["rows"].append(self._row)
            self._row = None

    def handle_data(self, data):
        if self._in_caption and self.tables:
            self.tables[-1]["caption"] += data.strip()
        if self._cell is not None:
            self._cell.append(data)


def _tables(page: Path) -> list[dict]:
    parser = _Tables()
    parser.feed(page.read_text("utf-8"))
    return parser.tables


#: How a page shows a number that ``metrics.json`` holds as ``null``: strict JSON has no
#: NaN or infinity (``scenes.files.dumps_strict``), so any non-finite value matches.
_NOT_FINITE = frozenset({"—", "n/a", "∞", "−∞"})


def _same_text(shown: str | None, value) -> bool:
    """Whether a page's ``shown`` text is ``value`` as the pages print it."""
    if value is None:
        return shown in _NOT_FINITE
    return shown == page_number(value)


def _close(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    a, b = float(a), float(b)
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return abs(a - b) <= RELATIVE_TOLERANCE * max(abs(a), abs(b), 1e-300)


def _csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def _float(text: str | None) -> float | None:
    return None if text in (None, "") else float(text)


def _key(m: dict) -> tuple[str, str, str]:
    return m["view"], m["region"], m["metric"]


def _page_metrics(folder: Path, data: dict) -> list[str]:
    """The page's Metrics tables against the records."""
    out = []
    tables = {t["caption"]: t for t in _tables(folder / "index.html")
              if "metrics" in t["class"].split()}
    for m in data["metrics"]:
        table = tables.get(m["view"])
        if table is None:
            out.append(f"{folder.name}: no Metrics table for view {m['view']}")
            continue
        header = table["header"]
        rows = [dict(zip(header, r, strict=False)) for r in table["rows"]]
        row = next((r for r in rows if r.get("region") == m["region"]
                    and r.get("metric") == m["metric"]), None)
        if row is None:
            out.append(f"{folder.name}: {_key(m)} missing from the page")
            continue
        interval = "—" if m["excess_ci95"] is None else "[{}, {}]".format(
            *(page_number(x) for x in m["excess_ci95"]))
        if row.get("95 % interval") != interval:
            out.append(f"{folder.name}: {_key(m)} 95 % interval: page "
                       f"{row.get('95 % interval')!r}, metrics.json {interval!r}")
        excess = row.get("excess (the method's own error)", "").split(" ")[0]
        for column, shown, value in (("pixels", row.get("pixels"), m["pixels"]),
                                     ("raw value", row.get("raw value"), m["value"]),
                                     ("excess", excess, m["excess"])):
            if not _same_text(shown, value):
                out.append(f"{folder.name}: {_key(m)} {column}: page {shown!r}, "
                           f"metrics.json {value!r}")
    return out


def _relmse(data: dict) -> dict | None:
    return next((m for m in data["metrics"]
                 if _key(m) == ("receiver0", "caustic", "relmse")), None)


def _studies(folder: Path, data: dict) -> list[str]:
    """The cost and convergence tables, the claims and the checks against the
    ``receiver0 / caustic / relmse`` record."""
    out = []
    record = _relmse(data)
    if record is None or record["excess"] is None:
        return out
    cost = folder / "cost_accuracy.csv"
    if cost.exists():
        rows = [r for r in _csv(cost) if r.get("series") != "reference"]
        if rows:
            row = rows[0]
            for column, value in (("excess", record["excess"]),
                                  ("excess_low", record["excess_ci95"][0]),
                                  ("excess_high", record["excess_ci95"][1])):
                if column in row and not _close(_float(row[column]), value):
                    out.append(f"{folder.name}: cost table's scene-settings {column} "
                               f"{row[column]} != metrics.json {value!r}")
    convergence = folder / "convergence.csv"
    settings = data.get("settings", {})
    if convergence.exists():
        rows = _csv(convergence)
        mine = [r for r in rows if r["estimator"] == settings.get("estimator")
                and r["safeguarded"] == str(settings.get("safeguarded"))
                and int(r["iteration"]) == settings.get("iterations")]
        for row in mine:
            if not _close(_float(row["excess_relmse"]), record["excess"]):
                out.append(f"{folder.name}: convergence table ({row['estimator']}, "
                           f"safeguarded {row['safeguarded']}, {row['iteration']} "
                           f"iterations) excess {row['excess_relmse']} != metrics.json "
                           f"{record['excess']!r}")
        out += _claims(folder, data, rows)
    for check in data.get("checks", []):
        if (check["kind"] == "method target" and check["metric"] == "relmse"
                and not _close(check["value"], record["excess"])):
            out.append(f"{folder.name}: method target relmse quotes {check['value']!r}, "
                       f"metrics.json {record['excess']!r}")
    return out


_FAILURE_ROW = re.compile(r'<tr class="fail failure">\s*<td><a href="([^"/]+)/index\.html"')
_CLAIM_NUMBERS = re.compile(r"after 1 iteration is (\S+), after (\d+) it is (\S+) ")


def _claims(folder: Path, data: dict, rows: list[dict[str, str]]) -> list[str]:
    """The one-iteration claim's excesses (its text) are the convergence table's."""
    out = []
    plain = {int(r["iteration"]): _float(r["excess_relmse"]) for r in rows
             if r["estimator"] == "modified" and r["safeguarded"] == "False"}
    for verdict in data.get("claim_verdicts", []):
        found = _CLAIM_NUMBERS.search(verdict.get("text", ""))
        if found is None or not verdict.get("quantity", "").startswith("excess"):
            continue
        last = int(found.group(2))
        for iteration, quoted in ((1, found.group(1)), (last, found.group(3))):
            table = plain.get(iteration)
            if table is not None and quoted != page_number(table):
                out.append(f"{folder.name}: claim {verdict['claim']!r} quotes {quoted} "
                           f"after {iteration} iterations, the convergence table "
                           f"{page_number(table)}")
    return out


def _index(out_dir: Path, comparisons: dict[Path, dict]) -> list[str]:
    """Each index cell's excess, interval and raw value against its record."""
    out = []
    index = out_dir / "index.html"
    if not index.exists():
        return [f"{out_dir}: no index.html"]
    text = index.read_text("utf-8")
    for folder in comparisons:
        if f'href="{folder.name}/index.html"' not in text:
            out.append(f"index.html has no row for {folder.name}")
    summary = next((t for t in _tables(index) if "summary" in t["class"].split()), None)
    if summary is None:
        return [*out, "index.html has no summary table"]
    for row in summary["rows"]:
        folder = next((f for f in comparisons if len(row) > 1
                       and row[0].startswith(comparisons[f]["scene"]["name"])
                       and row[1].startswith(comparisons[f]["method"]["name"])), None)
        if folder is None:
            continue
        data = comparisons[folder]
        cells = dict(zip(summary["header"], row, strict=False))
        for m in data["metrics"]:
            column = f"{m['metric']} {m['view']}, {m['region']}"
            if column not in cells or m["excess"] is None:
                continue
            cell = cells[column]
            expected = [page_number(m["excess"]), f"raw {page_number(m['value'])}"]
            if m["excess_ci95"] is not None:
                low, high = m["excess_ci95"]
                expected.append(f"[{page_number(low)}, {page_number(high)}]")
            missing = [e for e in expected if e not in cell]
            if missing:
                out.append(f"index.html {folder.name} {column}: {cell!r} lacks {missing}")
    return out


def disagreements(out_dir: str | Path) -> list[str]:
    """Every disagreement between the written copies of one quantity under
    ``out_dir`` (module docstring); empty when every number agrees.

    Parameters
    ----------
    out_dir : str or Path
        A ``caustics compare -o`` folder: ``index.html`` and one folder per scene and
        method with ``metrics.json`` and its page.
    """
    out_dir = Path(out_dir)
    comparisons = {}
    for path in sorted(out_dir.glob("*/metrics.json")):
        comparisons[path.parent] = json.loads(path.read_text("utf-8"))
    if not comparisons:
        return [f"{out_dir}: no comparison (no */metrics.json)"]
    # A failed comparison (no caustic, a stage that raised) still writes metrics.json
    # where it can, but its page is the failure's, with no tables to compare.
    index = out_dir / "index.html"
    failed = set(_FAILURE_ROW.findall(index.read_text("utf-8"))) if index.exists() else set()
    comparisons = {f: d for f, d in comparisons.items() if f.name not in failed}
    out = []
    pixels: dict[tuple, dict[str, set]] = {}
    for folder, data in comparisons.items():
        for m in data["metrics"]:
            key = (data["scene"]["name"], m["view"], m["region"])
            pixels.setdefault(key, {}).setdefault(data["method"]["name"], set()).add(
                m["pixels"])
        out += _page_metrics(folder, data)
        out += _studies(folder, data)
    for (scene, view, region), counts in pixels.items():
        if len(set().union(*counts.values())) > 1:
            out.append(f"{scene} {view}/{region}: metrics or methods scored over different "
                       f"pixels {({k: sorted(v) for k, v in counts.items()})}")
    return out + _index(out_dir, comparisons)
