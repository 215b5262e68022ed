#!/usr/bin/env python3
"""Ten Cate et al. (2002) settling sphere, cases E1-E4, with the immersed moving boundary (issue 5).

For each case and each resolution (cells per diameter N, dx = 15 mm / N) this script writes a scene
derived from validation/scenes/ten-cate-e1.toml, runs `lbm-server run` (which starts dem-client) in
the work folder validation/imb/work/ten_cate/<case>_N<n>/ (ignored by git: a reduced particles.csv, the
summary.json and the log), distils what the report needs of the run into its record in
validation/imb/results/ten_cate.json (committed), and writes REPORT.md and the charts in validation/imb/
from those records alone.

    python3 validation/imb/ten_cate.py run 3 6 7.5          # run the missing (case, N) pairs, then report
    python3 validation/imb/ten_cate.py run 6 --cases E1 E4  # a subset
    python3 validation/imb/ten_cate.py report               # only rebuild the report and charts from the results
    python3 validation/imb/ten_cate.py distil DIR           # DIR/<run>/ (folders as `run` leaves them) into the results
    python3 validation/imb/ten_cate.py run 6 --cases E4 --width 300 --height 320 --sim-time 2.5
                                        # a larger closed box (mm): run E4_N6_W300_H320, terminal (plateau) speed
    python3 validation/imb/ten_cate.py run 3 6 9 --cases E3 --op bgk    # another operator: runs E3_N<n>_bgk
    python3 validation/imb/ten_cate.py run 3 6 9 --cases E3 --op-suffix # TRT rerun: runs E3_N<n>_trt (timing)

Geometry: sphere d = 15 mm, rho_p = 1120 kg/m^3, closed box 100 x 100 x 160 mm, released from rest
with its *bottom* 120 mm above the floor (centre at z = 127.5 mm). Fluid properties and u_inf from
/work/shared/reference/ten-cate-2002.md. lattice.velocity_scale = u_inf, mach = 0.1, TRT, so
dt = 0.1/sqrt(3) dx / u_inf. Simulated time: 1.3 * 120 mm / u_inf (the sphere reaches the floor
region in every case: it settles slower than u_inf in the box).

Larger boxes (--width/--height, mm): width x width x height, all faces walls, the sphere centred in x, y and
released 32.5 mm below the lid as in the experiment; the terminal speed is the mean of -v_z over the rows
around its maximum that stay within 0.5 % of it. The experiment's box and folders are unchanged without them.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# The script's parts, beside it in validation/imb/: the cases and their scenes (ten_cate_scenes.py),
# running them (ten_cate_runs.py), the records taken from the runs (ten_cate_analysis.py), the charts
# (ten_cate_charts.py), the report's prose (ten_cate_findings.py, ten_cate_conclusions.py) and
# REPORT.md (ten_cate_report.py). This file: the command line, the scenes for a batch, the report built.
from ten_cate_analysis import (distil, mach_runs, op_results, op_wide_results, record,  # noqa: E402
                               resolutions_present, wide_results)
from ten_cate_charts import charts, op_chart, wide_charts  # noqa: E402
from ten_cate_findings import fmt  # noqa: E402
from ten_cate_report import report  # noqa: E402
from ten_cate_runs import BINARY, import_runs, run_folders, run_one  # noqa: E402
from ten_cate_scenes import BOX, CASES, MACH, OPERATOR, OPERATORS, lattice_numbers, run_dir, write_scene  # noqa: E402


def build_outputs():
    extra = [r for r in (record(c, n, m) for c, n, m in mach_runs()) if r is not None]
    results = []
    for n in resolutions_present():
        for case in CASES:
            r = record(case, n)
            if r is not None:
                results.append(r)
    wide = wide_results()
    ops = op_results()
    opw = op_wide_results()
    paths = charts(results, extra) + wide_charts(wide, results, extra) + op_chart(ops, results)
    slim = [{k: v for k, v in r.items() if k != "series"} for r in results]
    report(results, paths, extra, wide, ops, opw)
    for r in slim:
        print("%s N=%-4g peak %s m/s  err %s %%  tau %s  wall/sim %s  (%s)" % (
            r["case"], r["N"], fmt(r.get("peak_speed"), "%.4f"), fmt(r.get("peak_error_pct"), "%+.1f"),
            fmt(r.get("tau"), "%.4f"), fmt(r.get("wall_s_per_sim_s"), "%.0f"), r.get("exit_reason")))
    return results


def box_args(args):
    """(width, height) in m from --width/--height in mm; one alone takes the experiment's other side."""
    w = None if args.width is None else args.width * 1e-3
    h = None if args.height is None else args.height * 1e-3
    if (w is None) != (h is None):
        w = BOX[0] if w is None else w
        h = BOX[2] if h is None else h
    return w, h


def write_scenes(args):
    """The scenes of `run` without running them: DIR/<run folder name>/scene.toml, one line each on stdout
    (name, cells, steps, cell-steps) for the batch script to order and budget."""
    w, h = box_args(args)
    for n in args.N:
        for case in args.cases:
            name = os.path.basename(run_dir(case, n, args.mach, args.op, w, h, args.op_suffix))
            ln = lattice_numbers(case, n, args.mach, w, h, args.sim_time)
            if ln["tau"] < 0.5005:
                print("%s: tau %.5f < 0.5005, skipped" % (name, ln["tau"]), file=sys.stderr)
                continue
            os.makedirs(os.path.join(args.dir, name), exist_ok=True)
            write_scene(case, n, os.path.join(args.dir, name, "scene.toml"), args.mach, args.op, w, h,
                        args.sim_time, args.op_suffix)
            cells = ln["cells"][0] * ln["cells"][1] * ln["cells"][2]
            print("%s %dx%dx%d tau %.3f steps %d cell-steps %.3g" % (name, *ln["cells"], ln["tau"], ln["steps"],
                                                                     cells * ln["steps"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("run")
    a.add_argument("N", type=float, nargs="+", help="cells per diameter")
    a.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    a.add_argument("--force", action="store_true", help="rerun pairs that already have a summary.json")
    a.add_argument("--mach", type=float, default=MACH, help="Mach number of u_inf (default 0.1; others are runs <case>_N<n>_M<mach>)")
    a.add_argument("--op", default=OPERATOR, choices=OPERATORS,
                   help="collision operator (default trt; bgk and mrt are runs <case>_N<n>_<op>, MRT with the scene's default rates)")
    a.add_argument("--width", type=float, help="box width and depth in mm (default: the experiment's 100); with --height, "
                   "the runs are <case>_N<n>_W<w>_H<h>; the sphere stays centred in x, y, 32.5 mm below the lid")
    a.add_argument("--height", type=float, help="box height in mm (default: the experiment's 160)")
    a.add_argument("--sim-time", type=float, help="simulated time in s (default 1.3 x release gap / u_inf)")
    a.add_argument("--op-suffix", action="store_true",
                   help="put the operator in the folder name even for trt (runs <case>_N<n>_trt: a TRT rerun timed beside BGK and MRT)")
    sub.add_parser("report")
    sc = sub.add_parser("scenes", help="only write the scenes, DIR/<run folder name>/scene.toml (for a batch on another "
                        "machine: validation/gpu/run.sh); same options as run")
    sc.add_argument("dir")
    for action in a._actions:
        if action.dest not in ("help", "force", "dir"):
            sc._add_action(action)
    im = sub.add_parser("import", help="take the outputs of such a batch (DIR/<run folder name>/ with summary.json, "
                        "particles.csv, log.txt) into the work folder, distil them into the results, then rebuild the report")
    im.add_argument("dir")
    im.add_argument("--force", action="store_true", help="replace runs that already have a summary.json")
    di = sub.add_parser("distil", help="distil the run folders in DIR (named as `run` names them, with summary.json, "
                        "log.txt, particles.csv) into results/ten_cate.json, then rebuild the report")
    di.add_argument("dir")
    args = ap.parse_args()
    if args.cmd == "scenes":
        write_scenes(args)
        return
    if args.cmd == "import":
        distil(import_runs(args.dir, args.force))
    if args.cmd == "distil":
        distil(run_folders(args.dir))
    if args.cmd == "run":
        if not os.path.exists(BINARY):
            raise SystemExit("%s missing: cargo build --release --bins" % BINARY)
        w, h = box_args(args)
        for n in args.N:
            for case in args.cases:
                run_one(case, n, args.force, args.mach, args.op, w, h, args.sim_time, args.op_suffix)
    build_outputs()


if __name__ == "__main__":
    main()
