#!/usr/bin/env python
"""Put the whole table's means and t-tests per kind, beside the paper's, into a README: from the sections "Means
per kind and category" and "Paired t-tests across concepts" of ``docs/results/paper/report.md`` (what ``sb3-smc
report`` wrote), the rows over all concepts of a kind (means, the paper's, ours - paper; t-tests with a result; win
counts the paper gives), and the report's count of its claims' verdicts, copied between the README's markers
``<!-- paper-table:start -->`` and ``<!-- paper-table:end -->``. The per-category rows stay in the report, and the
numbers and counts where the report computes them; this only copies them. ``tools/paper_table.sh report``
runs it on the project's README with ``--brief`` (the claims count and the means only: the landing page stays short)
and on the results' own (``docs/results/paper/README.md``: everything).

Usage::

    python tools/readme_table.py [--report docs/results/paper/report.md] [--readme README.md] [--brief]
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

from sb3_smc.experiments.design import DEFAULT_METHODS
from sb3_smc.experiments.tables import CLAIMS_COUNT, CLAIMS_HEADING, MEANS_HEADING, TESTS_HEADING

ROOT = Path(__file__).resolve().parents[1]
START, END = "<!-- paper-table:start -->", "<!-- paper-table:end -->"
SECTIONS = (MEANS_HEADING, TESTS_HEADING)


def section(report: str, heading: str) -> list[str]:
    """The lines of the report's section ``heading`` (without it), up to the next section."""
    lines = report.splitlines()
    if heading not in lines:
        raise SystemExit(f"the report has no section {heading!r}: make it with tools/paper_table.sh report")
    start = lines.index(heading) + 1
    end = next((k for k in range(start, len(lines)) if lines[k].startswith("## ")), len(lines))
    return lines[start:end]


def cells(row: str) -> list[str]:
    """The cells of a Markdown table row."""
    return [cell.strip() for cell in row.strip().strip("|").split("|")]


KEEP = {  # a table's header -> which of its rows the README keeps
    "| kind | category |": lambda c: c[1] in ("all", "**paper** (all)") or c[1].startswith("ours - paper"),
    "| kind / category |": lambda c: "/" not in c[0] and c[2] != "0",
    "| kind | hierarchical |": lambda c: bool(c[4]),
}


def incomplete(table: list[str]) -> set[str]:
    """The kinds of the means table where one of the paper's methods has no mean over all concepts yet, or which
    have fewer concepts than the paper's (the table is partial)."""
    header = cells(table[0])
    rows = {(c[0], c[1]): c for c in map(cells, table[2:])}
    out = set()
    for (kind, label), ours in rows.items():
        paper = rows.get((kind, "**paper** (all)"))
        if label != "all" or paper is None:
            continue
        if ours[2] != paper[2] or any(ours[i] == "-" and paper[i] not in ("", "-") and header[i] in DEFAULT_METHODS
                                      for i in range(3, len(header))):
            out.add(kind)
    return out


def kind_rows(table: list[str]) -> list[str]:
    """``table`` (its lines) with the header and the rows over all concepts of a kind (:data:`KEEP`); in the means
    table, a kind not whole yet (:func:`incomplete`) keeps its categories' rows instead."""
    keep = next((rule for header, rule in KEEP.items() if table[0].startswith(header)), None)
    if keep is None:
        raise SystemExit(f"the report has a table the README does not know: {table[0]!r}")
    partial = incomplete(table) if table[0].startswith("| kind | category |") else set()
    return table[:2] + [row for row in table[2:]
                        if (cells(row)[1] != "all" if cells(row)[0] in partial else keep(cells(row)))]


def without_subset_methods(table: list[str]) -> list[str]:
    """The means table without the columns of our methods that ran on a subset of the concepts only (no mean over
    all of a kind's concepts: the sweep's settings, equal experience); the paper's methods keep theirs."""
    header = cells(table[0])
    rows = [cells(row) for row in table[2:]]
    over_all = [row for row in rows if row[1] == "all"]
    drop = {i for i in range(3, len(header)) if over_all and header[i] not in DEFAULT_METHODS
            and all(row[i] in ("", "-") for row in over_all)}
    if not drop:
        return table
    kept = [[c for i, c in enumerate(cells(line)) if i not in drop] for line in table]
    return ["|" + "|".join(row if k == 1 else [f" {c} " if c else " " for c in row]) + "|"
            for k, row in enumerate(kept)]


def tables_of(report: str, heading: str) -> list[list[str]]:
    """The Markdown tables (their lines) of the report's section ``heading``."""
    tables: list[list[str]] = []
    previous = ""
    for line in section(report, heading):
        if line.startswith("|"):
            if not previous.startswith("|"):
                tables.append([])
            tables[-1].append(line)
        previous = line
    return tables


PARTIAL = re.compile(r"^\*\*Partial results\*\*(?: \((?P<run>[^)]+)\))?:", re.MULTILINE)


def partial_note(report: str) -> str:
    """What of the table is still being run, for the block's first line: nothing when the report is whole; else the
    run directories the report names as partial, and whether the paper's methods (every one of them, on both kinds)
    have all their concepts all the same."""
    runs = [match["run"] for match in PARTIAL.finditer(report)]
    if not runs:
        return ""
    if not all(runs):  # a report over one directory names none
        return ", **partial: the table is still being run**"
    names = " and ".join(", ".join(f"`{run}`" for run in runs).rsplit(", ", 1))
    means = [table for table in tables_of(report, SECTIONS[0]) if table[0].startswith("| kind | category |")]
    kinds = {cells(row)[0] for table in means for row in table[2:]}
    columns = {column for table in means for column in cells(table[0])}
    whole = (kinds >= {"classification", "bring-about"} and columns >= set(DEFAULT_METHODS)
             and not any(incomplete(table) for table in means))
    return (f", **partial: {names} {'is' if len(runs) == 1 else 'are'} still being run**"
            + ("; the paper's methods have all their concepts" if whole else ""))



def claims_line(report: str, source: str) -> str:
    """The report's count of its claims' verdicts (the line under its claims table), linked to the table; ``""``
    when the report has no claims table."""
    if CLAIMS_HEADING not in report.splitlines():
        return ""
    counted = [line for line in section(report, CLAIMS_HEADING) if line.startswith(CLAIMS_COUNT)]
    if len(counted) != 1:
        raise SystemExit(f"the report's section {CLAIMS_HEADING!r} needs exactly one line beginning {CLAIMS_COUNT!r} "
                         f"(it has {len(counted)}): make it again with tools/paper_table.sh report")
    return f"**[The paper's claims]({source}#the-papers-claims)**" + counted[0].removeprefix(CLAIMS_COUNT)


def block(report: str, source: str, sections: tuple[str, ...] = SECTIONS) -> str:
    """The README's block: a line on what it is (whole, or what is still being run), the count of the claims
    reproduced, then the rows per kind of ``sections`` (default: both), headed in bold; the brief block (the means
    only) leaves out the methods run on a subset of the concepts (:func:`without_subset_methods`)."""
    lines = [START, "", f"From [the whole table's report]({source})" + partial_note(report)
             + "; scores in %, ours beside the paper's (Hay et al., AAAI-18).", ""]
    counted = claims_line(report, source)
    if counted:
        lines += [counted, ""]
    brief = tuple(sections) == SECTIONS[:1]
    for heading in sections:  # their tables only: the report explains them
        lines += [f"**{heading.removeprefix('## ')}**", ""]
        for table in tables_of(report, heading):
            rows = kind_rows(table)
            if brief and table[0].startswith("| kind | category |"):
                rows = without_subset_methods(rows)
            lines += [*rows, ""]
    return "\n".join([*lines, END])


def update(readme: str, new_block: str) -> str:
    """``readme`` with the text between its markers replaced by ``new_block``."""
    if readme.count(START) != 1 or readme.count(END) != 1 or readme.index(START) > readme.index(END):
        raise SystemExit(f"the README needs exactly one {START} and, after it, one {END}")
    before, rest = readme.split(START)
    _, after = rest.split(END)
    return before + new_block + after


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--report", type=Path, default=ROOT / "docs/results/paper/report.md")
    parser.add_argument("--readme", type=Path, default=ROOT / "README.md")
    parser.add_argument("--brief", action="store_true",
                        help="the means only, no t-tests (the landing page; the results' README has them all)")
    args = parser.parse_args(argv)
    for path, what in ((args.report, "the report (tools/paper_table.sh report makes it)"),
                       (args.readme, "the README to update")):
        if not path.is_file():
            raise SystemExit(f"{path} not found: {what}")
    source = Path(os.path.relpath(args.report.resolve(), args.readme.resolve().parent)).as_posix()
    report = args.report.read_text(encoding="utf-8")
    text = update(args.readme.read_text(encoding="utf-8"),
                  block(report, source, SECTIONS[:1] if args.brief else SECTIONS))
    tmp = args.readme.with_suffix(".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(args.readme)
    print(f"{args.readme}: the table from {args.report}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
