"""What the batch's table scripts (kernel_rows.py, coupled_rows.py) share: the command line, and
the table folded into BENCHMARKS.md between a pair of markers."""

import argparse
import pathlib
import sys


def fold(table, benchmarks, begin, end):
    """Replaces what lies between the markers `begin` and `end` of `benchmarks` with `table`."""
    text = benchmarks.read_text()
    if begin not in text or end not in text:
        sys.exit(f"{benchmarks}: no {begin} ... {end} markers")
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    benchmarks.write_text(f"{head}{begin}\n{table}\n{end}{tail}")


def main(doc, names, rows, head, markers):
    """SOURCE (a bench output, or the batch's folder holding NAME.txt for each of `names`) read by
    `rows` (a path's table rows) under `head`; printed, and folded into BENCHMARKS.md between
    `markers` (begin, end) unless --print."""
    p = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", type=pathlib.Path)
    p.add_argument("--benchmarks", type=pathlib.Path, default=pathlib.Path("BENCHMARKS.md"))
    p.add_argument("--print", action="store_true", help="print the rows, fold nothing")
    a = p.parse_args()
    files = [a.source] if a.source.is_file() else [a.source / f"{name}.txt" for name in names]
    table = [r for f in files if f.exists() for r in rows(f)]
    if not table:
        sys.exit(f"no rows in {a.source}")
    table = head + "\n" + "\n".join(table)
    print(table)
    if not a.print:
        fold(table, a.benchmarks, *markers)
        print(f"folded into {a.benchmarks}")
