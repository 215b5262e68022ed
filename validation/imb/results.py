#!/usr/bin/env python3
"""The compact results of the validation scripts of validation/imb/.

Each script runs `lbm-server run` into a folder of WORK (validation/imb/work/<script>/<run>/, which git
ignores), distils what its report needs from each run (a few numbers, and the reduced series its charts
draw) into one record, and keeps the records of all its runs in one committed file,
validation/imb/results/<script>.json: {"about": ..., "runs": {run name: record}}. A record is replaced
when its run is distilled again; the others stay. The reports, charts and tables are rebuilt from these
files alone (`<script>.py report`).

    python3 validation/imb/results.py imported NAME   # exit 0 if the GPU batch's run NAME is in a results
                                                      # file (validation/gpu/prepare.sh leaves it out)
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS = os.path.join(HERE, "results")
WORK = os.path.join(HERE, "work")


def path(script):
    return os.path.join(RESULTS, script + ".json")


def work(script):
    """The ignored folder where SCRIPT's runs are made: validation/imb/work/<script>/."""
    return os.path.join(WORK, script)


def load(script):
    """SCRIPT's results ({"about": ..., "runs": {name: record}}); empty runs where there is no file yet."""
    p = path(script)
    if not os.path.exists(p):
        return {"about": "", "runs": {}}
    with open(p) as f:
        return json.load(f)


def runs(script):
    """SCRIPT's records by run name."""
    return load(script)["runs"]


def merge(script, records, about=None):
    """SCRIPT's results with RECORDS ({name: record}) put in (replacing records of the same names)."""
    doc = load(script)
    doc["runs"].update(records)
    doc["runs"] = dict(sorted(doc["runs"].items()))
    if about is not None:
        doc["about"] = about
    os.makedirs(RESULTS, exist_ok=True)
    with open(path(script), "w") as f:
        f.write(dumps(doc) + "\n")


def dumps(value, indent=0):
    """JSON with one key per line, but each list of numbers or strings on one line (the series)."""
    pad = " " * indent
    if isinstance(value, dict):
        if not value:
            return "{}"
        items = ['%s %s: %s' % (pad, json.dumps(k), dumps(v, indent + 1)) for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(value, (list, tuple)) and any(isinstance(v, (dict, list, tuple)) for v in value):
        items = ["%s %s" % (pad, dumps(v, indent + 1)) for v in value]
        return "[\n" + ",\n".join(items) + "\n" + pad + "]"
    return json.dumps(value)


def summary(rows, rebuilt_by, note=""):
    """The table that opens a report: one row per case (case, reference, measured, error, the command that
    makes its run), then what rebuilds the report (REBUILT_BY, a command) and NOTE."""
    lines = ["| case | reference | measured | error | command |", "|---|---|---|---|---|"]
    lines += ["| %s | %s | %s | %s | `%s` |" % tuple(row) for row in rows]
    lines += ["", "The command of a row makes its run and adds it to the results; `%s` rebuilds this report "
              "from the results alone.%s" % (rebuilt_by, " " + note if note else "")]
    return "\n".join(lines)


def imported(name):
    """Whether the GPU batch's run NAME (bed_<case>, exp_<run> or a Ten Cate run) is in the results: a bed
    that ran (to its end or not), a Ten Cate run that completed."""
    if name.startswith("bed_"):
        return name[len("bed_"):] in runs("fluidized_bed")
    if name.startswith("exp_"):
        r = runs("experiment").get(name[len("exp_"):])
    else:
        r = runs("ten_cate").get(name)
    return r is not None and r.get("exit_code") == 0


if __name__ == "__main__":
    if sys.argv[1:2] == ["imported"] and len(sys.argv) == 3:
        sys.exit(0 if imported(sys.argv[2]) else 1)
    sys.exit(__doc__)
