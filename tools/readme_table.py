#!/usr/bin/env python
"""Put the answer of the whole table into a README: from ``docs/results/paper/report.md`` (what ``sb3-smc report``
wrote), one table of the paper's methods and the fair comparisons that answer its question (the means of base, curr
and canon, curr's and canon's leads over the flat SMC with their paired t-tests, the same lead where a call costs its
moves, at equal moves per episode, at equal experience, and curr's mean and lead under the setting of each reading
that fits the paper best, run on every concept), ours beside the paper's; the verdict in three sentences; the two
headline targets; and the count of the claims' verdicts, copied between the README's markers
``<!-- paper-table:start -->`` and ``<!-- paper-table:end -->``. Every number is the report's claims table's (and
the count under it): this only copies and arranges them, so the READMEs cannot disagree with the report.
``tools/paper_table.sh report`` runs it on the project's README (``--brief``: the answer table and the claims' count,
the rest a link away) and on the results' own (``docs/results/paper/README.md``).

Usage::

    python tools/readme_table.py [--report docs/results/paper/report.md] [--readme README.md] [--brief]
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

from pixelworld_env.atomic import atomic_write
from sb3_smc.experiments.claims import READINGS, VERDICTS
from sb3_smc.experiments.design import DEFAULT_METHODS
from sb3_smc.experiments.tables import CLAIMS_COUNT, CLAIMS_HEADING, MEANS_HEADING

ROOT = Path(__file__).resolve().parents[1]
START, END = "<!-- paper-table:start -->", "<!-- paper-table:end -->"
KINDS = ("classification", "bring-about")
ONE_STEP, MOVES, EQUAL_MOVES, CAP10, MOVES200, EXPERIENCE, MOVES_EXPERIENCE, CAP10_EXPERIENCE = (
    reading.name for reading in READINGS)
HEADLINE = ("cl_self-left-of-two-objects-vs-one", "ba_self-in-container_from_between-potential-containers")
LEAD = "{m} above base (paired t-test)"
ANSWER_ROWS = (  # (what the row says, the claims table's statement after "<kind>: ", its column)
    ("the flat SMC (base): mean", "mean of base", ONE_STEP),
    ("curr: mean (a call is one step)", "mean of curr", ONE_STEP),
    ("canon: mean (a call is one step)", "mean of canon", ONE_STEP),
    ("curr above base (a call is one step)", LEAD.format(m="curr"), ONE_STEP),
    ("canon above base (a call is one step)", LEAD.format(m="canon"), ONE_STEP),
    ("curr above base, a call costing its moves (curr-moves)", LEAD.format(m="curr"), MOVES),
    ("curr above base given 400 moves an episode (equal moves)", LEAD.format(m="curr"), EQUAL_MOVES),
    ("curr above base at equal experience (a call is one step)", LEAD.format(m="curr"), EXPERIENCE),
    ("curr above base at equal experience (a call costs its moves)", LEAD.format(m="curr"), MOVES_EXPERIENCE),
    ("curr-cap10 above base at equal experience (a call is one step, cut after 10 moves)", LEAD.format(m="curr"),
     CAP10_EXPERIENCE),
)
BEST_ROWS = (  # the setting of each reading that fits the paper best, on every concept (the results page only)
    ("curr-cap10: mean (a call is one step, cut after 10 moves)", "mean of curr", CAP10),
    ("curr-cap10 above base", LEAD.format(m="curr"), CAP10),
    ("curr-moves-200: mean (calls cost their moves, 200 moves an episode)", "mean of curr", MOVES200),
    ("curr-moves-200 above base", LEAD.format(m="curr"), MOVES200),
)


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


def table_of(report: str, heading: str) -> dict[str, dict[str, str]]:
    """The first table of the report's section ``heading``: its rows by their first cell, each row's cells by the
    table's header (``{}`` where the report has no such section)."""
    if heading not in report.splitlines():
        return {}
    tables = tables_of(report, heading)
    if not tables:
        return {}
    header = cells(tables[0][0])
    return {row[0]: dict(zip(header, row, strict=False)) for row in map(cells, tables[0][2:])}


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
    means = [table for table in tables_of(report, MEANS_HEADING) if table[0].startswith("| kind | category |")]
    kinds = {cells(row)[0] for table in means for row in table[2:]}
    columns = {column for table in means for column in cells(table[0])}
    whole = (kinds >= set(KINDS) and columns >= set(DEFAULT_METHODS)
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


def split_verdict(cell: str) -> tuple[str, str]:
    """A claims cell as (ours, verdict): ``"89.8 [88.4, 91.0]: exceeded"`` -> ``("89.8 [88.4, 91.0]", "exceeded")``;
    a cell without one of the claims' verdicts (``not run``, ``not judged: partial``, ``same as one step``, empty)
    -> ``("", cell)``."""
    ours, _, verdict = cell.rpartition(": ")
    return (ours, verdict) if ours and verdict in VERDICTS else ("", cell)


Rows = list[tuple[str, dict[str, tuple[str, str, str]]]]
"""The answer table's rows: what each says, and per kind (ours, verdict, the paper's)."""


def answer_rows(report: str, best: bool = True) -> Rows:
    """The answer table's rows from the report's claims table (with ``best``, the best settings' rows too); a row no
    kind has a result for is left out."""
    claims = table_of(report, CLAIMS_HEADING)
    wanted = (*ANSWER_ROWS, *(BEST_ROWS if best else ()))
    missing = [f"{kind}: {statement}" for _, statement, _ in wanted for kind in KINDS
               if claims and f"{kind}: {statement}" not in claims]
    if missing:
        raise SystemExit(f"the report's claims table has no statement {missing[0]!r}: the answer table reads it "
                         "(make the report again with tools/paper_table.sh report, or update ANSWER_ROWS)")
    rows: Rows = []
    for label, statement, column in wanted:
        found = {}
        for kind in KINDS:
            row = claims.get(f"{kind}: {statement}", {})
            ours, verdict = split_verdict(row.get(column, ""))
            if ours:
                found[kind] = (ours, verdict, row["paper"])
        if found:
            rows.append((label, found))
    return rows


def answer_table(rows: Rows) -> list[str]:
    """The answer table (Markdown lines) of ``rows``: a row per comparison, ours with its interval and verdict beside
    the paper's, per kind; ``[]`` without rows (the report has no claims table)."""
    if not rows:
        return []
    lines = ["| | classification: ours | paper | bring-about: ours | paper |", "|---|---|---|---|---|"]
    for label, found in rows:
        line = [label]
        for kind in KINDS:
            ours, verdict, paper = found.get(kind, ("-", "", ""))
            line += [f"{ours} ({verdict})" if verdict else ours, paper]
        lines.append("| " + " | ".join(line) + " |")
    return lines


_PHRASES = {"exceeded": "above the paper's", "reproduced": "as the paper's", "short": "short of the paper's claim",
            "opposite": "the opposite sign to the paper's", "not significant": "not significant"}


def _brief(ours: str, paper: str = "") -> str:
    """A cell's number without its interval, its p, the paper's number and the cell's subset in brackets:
    ``"+8.8 [-4.6, +23.9] on 7 swept targets; t(6) = 1.43, p = 0.2"`` -> ``"+8.8 (p = 0.2; 7 swept targets)"``."""
    subset = re.search(r"\] on (\d+ [^;]+)", ours)
    p = re.search(r"p = ([^ ;)]+)", ours)
    said = [text for text in (p and f"p = {p[1]}", paper and f"paper {paper.split(';')[0]}", subset and subset[1])
            if text]
    return ours.split(" ")[0] + (f" ({'; '.join(said)})" if said else "")


_BY_SIGN = {"reproduced": "in the paper's direction, p < 0.05", "short": "its interval holding zero",
            "opposite": "the opposite of the paper's", "not significant": "in the paper's direction, not significant"}
"""The verdicts in words where only the sign is judged (at equal experience: the paper's number is not)."""


def _both(found: dict[str, tuple[str, str, str]], paper: bool = False, by_sign: bool = False) -> str:
    """The two kinds' numbers (with the paper's), then their verdicts in words (``by_sign``: of a sign)."""
    said = " and ".join(f"{_brief(found[kind][0], found[kind][2] if paper else '')} on {kind}"
                        for kind in KINDS if kind in found)
    verdicts = [found[kind][1] for kind in KINDS if kind in found]
    if len(set(verdicts)) == 1:
        words = (_BY_SIGN if by_sign else _PHRASES).get(verdicts[0], verdicts[0]) + (" on both kinds"
                                                                                   if len(verdicts) == 2 else "")
    else:
        words = ", ".join(f"{found[kind][1]} on {kind}" for kind in KINDS if kind in found)
    return f"{said}: {words}"


def beyond(report: str, method: str) -> str:
    """From the report's equal-experience summary, on how many of ``method``'s targets the flat SMC's curve ends
    below its experience (the flat SMC read at its best point there: the lead an upper bound unless the flat SMC had
    converged), as a remark; ``""`` where the report says none."""
    summary = next((line for line in report.splitlines() if line.startswith("**At equal experience**")), "")
    found = re.search(rf"{re.escape(method)}: ahead on \d+ of (\d+) targets \([^)]*?on (\d+) the flat SMC's curve "
                      r"ends below its experience\)", summary)
    return (f" (on {found[2]} of its {found[1]} targets the flat SMC's curve ends below {method}'s experience: "
            "read at its best point)") if found else ""


def verdict(answer: Rows, report: str = "") -> list[str]:
    """The verdict in three sentences, a list item each, from the answer table's rows (so from the report's
    numbers): the paper's reading of a call as one step, the readings that make the comparison fair in moves, and
    equal experience (on every concept first, then on the sweep's; from ``report``, where the flat SMC's curve ends
    below curr-cap10's experience); a sentence whose rows are missing is left out."""
    rows = dict(answer)
    remark = {ANSWER_ROWS[9][0]: beyond(report, "curr-cap10")}

    def said(parts: tuple[tuple[str, str], ...], by_sign: bool = False) -> str:
        return "; ".join(f"{what}, {_both(rows[label], by_sign=by_sign)}{remark.get(label, '')}"
                         for what, label in parts if label in rows)

    sentences = []
    if lead := rows.get(ANSWER_ROWS[3][0]):
        sentences.append(f"- **A call as one step** (the paper's count): curr leads the flat SMC by "
                         f"{_both(lead, paper=True)}.")
    if fair := said((("with each call costing its moves", ANSWER_ROWS[5][0]),
                     ("against a flat SMC given 400 moves an episode", ANSWER_ROWS[6][0]),
                     ("with calls costing their moves in 200 moves an episode (that reading's best setting)",
                      BEST_ROWS[3][0]))):
        sentences.append(f"- **Fair in moves**, curr's lead over the flat SMC is: {fair}.")
    if equal := said((("with a call cut after 10 moves", ANSWER_ROWS[9][0]),
                      ("with a call as one step", ANSWER_ROWS[7][0]),
                      ("with each call costing its moves", ANSWER_ROWS[8][0])), by_sign=True):
        sentences.append(f"- **At equal experience** (the flat SMC read off its curve of experience), it is: {equal}.")
    return sentences


def headline(report: str) -> list[str]:
    """The two headline targets' base, curr and canon (and curr-moves) where the report has them, ours beside the
    paper's, one sentence."""
    claims = table_of(report, CLAIMS_HEADING)
    said = []
    for target in HEADLINE:
        scores = {m: (ours, claims[f"{target}: {m}"]["paper"]) for m in ("base", "curr", "canon")
                  if (ours := split_verdict(claims.get(f"{target}: {m}", {}).get(ONE_STEP, ""))[0])}
        if not scores:
            continue
        moves = split_verdict(claims.get(f"{target}: curr", {}).get(MOVES, ""))[0]
        said.append(f"`{target}` " + ", ".join(f"{m} {ours.split(' [')[0]}" for m, (ours, _) in scores.items())
                    + " (paper " + ", ".join(paper for _, paper in scores.values()) + ")"
                    + (f", curr-moves {moves.split(' [')[0]}" if moves else ""))
    return [f"**The paper's two headline targets** (best seed of 5): {'; '.join(said)}."] if said else []


def block(report: str, source: str, brief: bool = False) -> str:
    """The README's block: a line on what it is (whole, or what is still being run), the answer table, the
    verdict, the headline targets and the count of the claims' verdicts; ``brief`` (the landing page): without the
    best settings' rows, the verdict and the headline targets, which the results page beside the report holds."""
    lines = [START, "", f"From [the whole table's report]({source})" + partial_note(report)
             + "; scores in %, ours (95 % bootstrap interval; a lead over all of a kind's concepts resamples the "
             "concepts too) beside the paper's (Hay et al., AAAI-18), with the verdict.", ""]
    rows = answer_rows(report, best=not brief)
    parts = [answer_table(rows)]
    if brief:
        page = (Path(source).parent / "README.md").as_posix()
        parts.append([f"The verdict, the paper's headline targets and the best setting of each reading: "
                      f"[the results page]({page})."] if rows else [])
    else:
        parts += [verdict(rows, report), headline(report)]
    for part in parts:
        if part:
            lines += [*part, ""]
    counted = claims_line(report, source)
    if counted:
        lines += [counted, ""]
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
                        help="the landing page's block: no best settings' rows, verdict or headline targets")
    args = parser.parse_args(argv)
    for path, what in ((args.report, "the report (tools/paper_table.sh report makes it)"),
                       (args.readme, "the README to update")):
        if not path.is_file():
            raise SystemExit(f"{path} not found: {what}")
    source = Path(os.path.relpath(args.report.resolve(), args.readme.resolve().parent)).as_posix()
    report = args.report.read_text(encoding="utf-8")
    atomic_write(args.readme, update(args.readme.read_text(encoding="utf-8"), block(report, source, args.brief)))
    print(f"{args.readme}: the answer from {args.report}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
