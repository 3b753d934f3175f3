#!/usr/bin/env python
"""Put the whole table's category means and t-tests, beside the paper's, into the README: the sections "Means per
kind and category" and "Paired t-tests across concepts" of ``docs/results/paper/report.md`` (what ``sb3-smc report``
wrote), copied between the README's markers ``<!-- paper-table:start -->`` and ``<!-- paper-table:end -->``. The
numbers stay where the report computes them; this only copies them.

Usage::

    python tools/readme_table.py [--report docs/results/paper/report.md] [--readme README.md]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
START, END = "<!-- paper-table:start -->", "<!-- paper-table:end -->"
SECTIONS = ("## Means per kind and category (Fig. 5a/5d)", "## Paired t-tests across concepts")


def section(report: str, heading: str) -> list[str]:
    """The lines of the report's section ``heading`` (without it), up to the next section."""
    lines = report.splitlines()
    if heading not in lines:
        raise SystemExit(f"the report has no section {heading!r}: make it with tools/paper_table.sh report")
    start = lines.index(heading) + 1
    end = next((k for k in range(start, len(lines)) if lines[k].startswith("## ")), len(lines))
    return lines[start:end]


def block(report: str, source: str) -> str:
    """The README's block: a line on what it is (partial or whole), then the two sections, headed in bold."""
    partial = "**Partial results**" in report
    lines = [START, "", f"From [the whole table's report]({source})" + (
        ", **partial: the table is still being run** (a method without all of a kind's concepts has no mean there)"
        if partial else "") + "; scores in %, ours beside the paper's (Hay et al., AAAI-18).", ""]
    for heading in SECTIONS:  # their tables only: the report explains them
        body = section(report, heading)
        tables = [line for k, line in enumerate(body) if line.startswith("|")
                  or (not line.strip() and 0 < k < len(body) - 1 and body[k - 1].startswith("|")
                      and any(b.startswith("|") for b in body[k + 1:]))]
        lines += [f"**{heading.removeprefix('## ')}**", "", *tables, ""]
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
    args = parser.parse_args(argv)
    source = Path(args.report).resolve().relative_to(Path(args.readme).resolve().parent).as_posix()
    text = update(args.readme.read_text(encoding="utf-8"), block(args.report.read_text(encoding="utf-8"), source))
    tmp = args.readme.with_suffix(".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(args.readme)
    print(f"{args.readme}: the table from {args.report}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
