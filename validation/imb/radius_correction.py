#!/usr/bin/env python3
"""Ten Cate runs in a larger box again with `coupling.radius_correction = "calibrated"` (issue 5).

For each run folder of validation/imb/runs/ named on the command line (a larger-box run, whose
terminal speed is a plateau), this script takes its scene.toml, adds the correction, runs
`lbm-server run` into validation/imb/runs_rc/<run>/, keeps the sphere's rows of particles.csv
(reduced as in runs/), and writes validation/imb/RADIUS_CORRECTION.md: the terminal (plateau)
speed of each run drawn at its radius and drawn with the calibrated hydrodynamic radius deficit
(docs/imb.md, "Radius correction"), both against u_inf.

    python3 validation/imb/radius_correction.py E1_N6_M0p05_W200_H240 E3_N6_W200_H240
    python3 validation/imb/radius_correction.py --report      # only the report, from runs_rc/

LBM_SERVER names another lbm-server (as for ten_cate.py).
"""

import argparse
import json
import os
import re
import shutil
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import ten_cate  # noqa: E402  (the same box geometry, plateau and reduction)

OUT = os.path.join(HERE, "runs_rc")
REPORT = os.path.join(HERE, "RADIUS_CORRECTION.md")


def corrected_scene(text, timeout=None):
    """The scene with the calibrated correction (refused if it already has a [coupling] table) and,
    if given, a longer coupling.timeout (a run niced behind other work waits long for a step)."""
    if re.search(r"^\[coupling\]", text, flags=re.M):
        raise SystemExit("the scene already has a [coupling] table: add the correction by hand")
    extra = "timeout = %g\n" % timeout if timeout else ""
    return text.rstrip("\n") + "\n\n[coupling]\nradius_correction = \"calibrated\"\n" + extra


def run(name, timeout=None):
    src = os.path.join(ten_cate.RUNS, name)
    scene = open(os.path.join(src, "scene.toml")).read()
    out = os.path.join(OUT, name)
    code, work = ten_cate.run_scene(out, corrected_scene(scene, timeout))
    if code != 0:
        raise SystemExit("%s: lbm-server exited %d (see %s/log.txt)" % (name, code, out))
    shutil.copy(os.path.join(work, "summary.json"), os.path.join(out, "summary.json"))
    ten_cate.reduce_csv(os.path.join(work, "particles.csv"), os.path.join(out, "particles.csv"))
    shutil.rmtree(work)


def terminal(folder):
    """(case, N, tau, terminal speed, error vs u_inf [%]) of a larger-box run folder."""
    m = ten_cate.DIR_RE.match(os.path.basename(folder))
    case = m.group(1)
    cols = ten_cate.load_series(os.path.join(folder, "particles.csv"))
    gap = [z - ten_cate.R for z in cols["z"]]
    speed = [-v for v in cols["vz"]]
    p = ten_cate.plateau(cols["time"], gap, speed)
    u_inf = ten_cate.CASES[case]["u_inf"]
    with open(os.path.join(folder, "log.txt")) as f:
        tau = float(re.search(r"tau ([0-9.]+)", f.read()).group(1))
    return case, float(m.group(2).replace("p", ".")), tau, p["terminal_speed"], 100.0 * (p["terminal_speed"] - u_inf) / u_inf


def box_of(name):
    """The case, Mach number and box of a run folder's name, without its resolution."""
    return re.sub(r"_N[0-9p]+", "", name)


def refinement(series):
    """Per case and box run at two or more resolutions: the error at the radius and corrected against
    N, and how far each moves over the resolutions (max - min, in points)."""
    lines = []
    for box, points in sorted(series.items()):
        if len(points) < 2:
            continue
        points.sort()
        at = [e for _, e, _ in points]
        rc = [e for _, _, e in points]
        lines.append("| %s | %s | %s | %s | %.1f | %.1f |" % (
            box, ", ".join("%g" % n for n, _, _ in points), ", ".join("%+.1f" % e for e in at),
            ", ".join("%+.1f" % e for e in rc), max(at) - min(at), max(rc) - min(rc)))
    return lines


def report():
    rows = []
    series = {}
    for name in sorted(os.listdir(OUT)):
        corrected = os.path.join(OUT, name)
        if not os.path.exists(os.path.join(corrected, "summary.json")):
            continue
        case, n, tau, v_rc, e_rc = terminal(corrected)
        _, _, _, v, e = terminal(os.path.join(ten_cate.RUNS, name))
        with open(os.path.join(corrected, "log.txt")) as f:
            drawn = re.search(r"drawn larger by (-?[0-9.]+) cells\^2", f.read())
        product = float(drawn.group(1)) if drawn else float("nan")
        r_cells = n / 2.0
        rows.append("| %s | %s | %g | %.3f | %.3f | %.4f | %+.1f | %.4f | %+.1f |" % (
            name, case, n, tau, product / r_cells, v, e, v_rc, e_rc))
        series.setdefault(box_of(name), []).append((n, e, e_rc))
    text = ("# Ten Cate in larger boxes with the calibrated radius correction\n\n"
            "Written by `python3 validation/imb/radius_correction.py` (lavapipe, this repository's CPU "
            "machine). Each run of validation/imb/runs/ named in the first column run again with "
            "`coupling.radius_correction = \"calibrated\"` (docs/imb.md, \"Radius correction\": the sphere "
            "drawn on the lattice larger by the hydrodynamic radius deficit measured on the Zick-Homsy "
            "array at the lattice's tau, scaled as 1 / radius), everything else the same. Terminal speed: "
            "the plateau of ten_cate.py (the mean of -v_z over the rows within 0.5 % of the maximum). "
            "Error against u_inf, the unbounded terminal velocity of the reference.\n\n"
            "| run | case | cells per diameter | tau | drawn larger by (cells) | terminal, at its radius [m/s] | "
            "error [%] | terminal, corrected [m/s] | error [%] |\n"
            "|---|---|---:|---:|---:|---:|---:|---:|---:|\n" + "\n".join(rows) + "\n")
    lines = refinement(series)
    if lines:
        text += ("\n## Refinement\n\nThe same case in the same box at several resolutions: if the "
                 "sphere's error at its radius is the boundary's deficit (falling as 1 / N^2, the relative "
                 "radius error), the corrected error stays put as N grows while the error at the radius "
                 "moves; if the deficit does not act in that flow, the corrected error moves instead. "
                 "Errors against u_inf in %, the spread is max - min over the resolutions in points.\n\n"
                 "| case and box | cells per diameter | error at the radius | error corrected | "
                 "spread at the radius | spread corrected |\n|---|---|---|---|---:|---:|\n"
                 + "\n".join(lines) + "\n")
        alone = sorted({b.split("_")[0] for b, p in series.items() if len(p) < 2}
                       - {b.split("_")[0] for b, p in series.items() if len(p) >= 2})
        if alone:
            text += ("\nNot in this table (each box at one resolution only; see the table above): %s.\n"
                     % ", ".join(alone))
    with open(REPORT, "w") as f:
        f.write(text)
    print(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="*", help="run folders of validation/imb/runs/ (larger boxes)")
    ap.add_argument("--report", action="store_true", help="only write the report from runs_rc/")
    ap.add_argument("--timeout", type=float, help="coupling.timeout [s] of the runs (default: the scene's)")
    args = ap.parse_args()
    if not args.report:
        for name in args.runs:
            if os.path.exists(os.path.join(OUT, name, "summary.json")):
                print("%s: already run, skipped" % name)
                continue
            print("%s: running" % name, flush=True)
            run(name, args.timeout)
    report()


if __name__ == "__main__":
    main()
