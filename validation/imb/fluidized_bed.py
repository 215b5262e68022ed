#!/usr/bin/env python3
"""The fluidized bed of validation/scenes/fluidized-bed.toml at Re 200 and 400 with each operator.

The seed paper's bed (BGK, 10 cells per diameter) ran at Re 200 and diverged at Re 400. For each
case this script writes the scene with its operator and inflow (Re = U d / nu) into the ignored work
folder validation/imb/work/fluidized_bed/<operator>_Re<re>/, runs `lbm-server run` there (or records why
the scene was refused), keeps summary.json, the log and the grains' mean height per output row, distils
what the report needs (the run's outcome, the bed's voidage and the weight the liquid carries) into the
case's record in validation/imb/results/fluidized_bed.json, and writes validation/imb/FLUIDIZED_BED.md from
the records: whether each case ran to its end, and where it did, the expanded bed's voidage against
Richardson & Zaki (1954).

    python3 validation/imb/fluidized_bed.py                  # every case (about an hour on lavapipe)
    python3 validation/imb/fluidized_bed.py mrt_Re400        # one case
    python3 validation/imb/fluidized_bed.py --report         # only the report, from the results
    python3 validation/imb/fluidized_bed.py distil DIR       # DIR/<case>/ (folders as a run leaves them) into the results
    python3 validation/imb/fluidized_bed.py held             # the bed held still at 6 and 9 cells, and with the
                                                             # superposition term at 6 (25 min)
    python3 validation/imb/fluidized_bed.py held-superposed  # only the last (4 min)
    python3 validation/imb/fluidized_bed.py scenes DIR       # write the GPU cases' scenes (validation/gpu/)
    python3 validation/imb/fluidized_bed.py held-scenes DIR  # the held bed's GPU scenes
    python3 validation/imb/fluidized_bed.py import DIR       # take a GPU batch's runs into the results

LBM_SERVER names another lbm-server (as for ten_cate.py).
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# The script's parts, beside it in validation/imb/: the cases and their scenes (fluidized_bed_scenes.py),
# running them (fluidized_bed_runs.py), what a run's record takes from it (fluidized_bed_analysis.py),
# the correlations the bed is measured against (fluidized_bed_references.py) and FLUIDIZED_BED.md
# (fluidized_bed_report.py). This file: the command line.
from fluidized_bed_analysis import distil  # noqa: E402
from fluidized_bed_report import report  # noqa: E402
from fluidized_bed_runs import import_runs, run, run_held  # noqa: E402
from fluidized_bed_scenes import (CASES, GPU_CASES, HELD_CELLS, HELD_SUPERPOSED_CELLS, name, write_held_scenes,  # noqa: E402
                                  write_scenes)


def main():
    if sys.argv[1:2] == ["held"]:
        for cells in HELD_CELLS:
            run_held(cells)
        for cells in HELD_SUPERPOSED_CELLS:
            run_held(cells, "mrts")
        report()
        return
    if sys.argv[1:2] == ["held-superposed"]:
        for cells in HELD_SUPERPOSED_CELLS:
            run_held(cells, "mrts")
        report()
        return
    if sys.argv[1:2] in (["scenes"], ["held-scenes"], ["import"], ["distil"]):
        if len(sys.argv) != 3:
            raise SystemExit("usage: fluidized_bed.py %s DIR" % sys.argv[1])
        if sys.argv[1] == "scenes":
            write_scenes(sys.argv[2])
            return
        if sys.argv[1] == "held-scenes":
            write_held_scenes(sys.argv[2])
            return
        if sys.argv[1] == "distil":
            distil([os.path.join(sys.argv[2], entry) for entry in sorted(os.listdir(sys.argv[2]))])
        else:
            import_runs(sys.argv[2])
        report()
        return
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("cases", nargs="*", help="cases to run (e.g. mrt_Re400); default: all")
    parser.add_argument("--report", action="store_true", help="only write the report from the results")
    args = parser.parse_args()
    if not args.report:
        wanted = args.cases or [name(*c) for c in CASES]
        for case in CASES + GPU_CASES:
            if name(*case) in wanted:
                run(*case)
    report()


if __name__ == "__main__":
    main()
