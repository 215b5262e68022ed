#!/usr/bin/env python3
"""Ten Cate runs in a larger box again with `coupling.radius_correction = "calibrated"` (issue 5).

For each Ten Cate run named on the command line (a larger-box run of validation/imb/ten_cate.py,
whose terminal speed is a plateau), this script takes its scene (from ten_cate.py's work folder, or
written again by ten_cate.py for the steps its record ran), adds the correction, runs `lbm-server run`
into the ignored work folder validation/imb/work/radius_correction/<run>/ (the sphere's rows of
particles.csv reduced as ten_cate.py reduces them), distils its terminal speed into its record in
validation/imb/results/radius_correction.json, and writes validation/imb/RADIUS_CORRECTION.md from the
records: the terminal (plateau) speed of each run drawn at its radius (its record in
results/ten_cate.json) and drawn with the calibrated hydrodynamic radius deficit (docs/imb.md, "Radius
correction"), both against u_inf.

    python3 validation/imb/radius_correction.py E1_N6_M0p05_W200_H240 E3_N6_W200_H240
    python3 validation/imb/radius_correction.py --report      # only the report, from the results
    python3 validation/imb/radius_correction.py --distil DIR  # DIR/<run>/ (folders as a run leaves them) into the results

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
import results as compact  # noqa: E402
import ten_cate_analysis  # noqa: E402  (validation/imb/ten_cate.py's parts: the records, the series, the plateau)
import ten_cate_runs  # noqa: E402  (a scene run, the csv reduction)
import ten_cate_scenes  # noqa: E402  (the same box geometry, the run names, the scene writer)

SCRIPT = "radius_correction"
OUT = compact.work(SCRIPT)
REPORT = os.path.join(HERE, "RADIUS_CORRECTION.md")


def corrected_scene(text, timeout=None):
    """The scene with the calibrated correction (refused if it already has a [coupling] table) and,
    if given, a longer coupling.timeout (a run niced behind other work waits long for a step)."""
    if re.search(r"^\[coupling\]", text, flags=re.M):
        raise SystemExit("the scene already has a [coupling] table: add the correction by hand")
    extra = "timeout = %g\n" % timeout if timeout else ""
    return text.rstrip("\n") + "\n\n[coupling]\nradius_correction = \"calibrated\"\n" + extra


def ten_cate_scene(name):
    """The scene of the Ten Cate run NAME: its scene.toml in ten_cate.py's work folder, or the scene
    ten_cate.py writes for it now, for the steps its record ran."""
    kept = os.path.join(ten_cate_scenes.RUNS, name, "scene.toml")
    if os.path.exists(kept):
        return open(kept).read()
    sp, r = ten_cate_scenes.spec_of(name), ten_cate_analysis.records().get(name)
    if sp is None or r is None:
        raise SystemExit("%s: no such Ten Cate run in %s" % (name, compact.path("ten_cate")))
    path = os.path.join(OUT, name + ".scene.toml")
    os.makedirs(OUT, exist_ok=True)
    ten_cate_scenes.write_scene(sp["case"], sp["n"], path, sp["mach"], sp["op"], sp["width"], sp["height"],
                         (r["steps_requested"] - 0.5) * r["dt"], sp["explicit"])
    return open(path).read()


def run(name, timeout=None):
    scene = ten_cate_scene(name)
    out = os.path.join(OUT, name)
    code, work = ten_cate_runs.run_scene(out, corrected_scene(scene, timeout))
    if code != 0:
        raise SystemExit("%s: lbm-server exited %d (see %s/log.txt)" % (name, code, out))
    shutil.copy(os.path.join(work, "summary.json"), os.path.join(out, "summary.json"))
    ten_cate_runs.reduce_csv(os.path.join(work, "particles.csv"), os.path.join(out, "particles.csv"))
    shutil.rmtree(work)
    distil([out])


def distil(folders):
    """The records of the corrected run FOLDERS (named as the Ten Cate run they repeat) into the results:
    case, N, tau, terminal speed and its error, and how much larger the sphere was drawn."""
    out = {}
    for folder in folders:
        if not os.path.exists(os.path.join(folder, "summary.json")):
            continue
        case, n, tau, v, e = terminal(folder)
        with open(os.path.join(folder, "log.txt")) as f:
            drawn = re.search(r"drawn larger by (-?[0-9.]+) cells\^2", f.read())
        out[os.path.basename(os.path.normpath(folder))] = dict(
            case=case, N=n, tau=tau, terminal_speed=v, terminal_error_pct=e,
            drawn_larger_cells2=float(drawn.group(1)) if drawn else float("nan"))
    compact.merge(SCRIPT, out, about="Ten Cate in larger boxes with the calibrated radius correction: one record "
                  "per run of validation/imb/radius_correction.py (its tau, terminal speed and error against u_inf, "
                  "and the product the log names, radius x how much larger the sphere is drawn, in cells^2).")


def terminal(folder):
    """(case, N, tau, terminal speed, error vs u_inf [%]) of a larger-box run folder."""
    m = ten_cate_scenes.DIR_RE.match(os.path.basename(folder))
    case = m.group(1)
    cols = ten_cate_analysis.load_series(os.path.join(folder, "particles.csv"))
    gap = [z - ten_cate_scenes.R for z in cols["z"]]
    speed = [-v for v in cols["vz"]]
    p = ten_cate_analysis.plateau(cols["time"], gap, speed)
    u_inf = ten_cate_scenes.CASES[case]["u_inf"]
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
    rows, opening = [], []
    series = {}
    at_radius = ten_cate_analysis.records()
    for name, rc in sorted(compact.runs(SCRIPT).items()):
        case, n, tau, v_rc, e_rc = rc["case"], rc["N"], rc["tau"], rc["terminal_speed"], rc["terminal_error_pct"]
        v, e = at_radius[name]["terminal_speed"], at_radius[name]["terminal_error_pct"]
        product = rc["drawn_larger_cells2"]
        r_cells = n / 2.0
        rows.append("| %s | %s | %g | %.3f | %.3f | %.4f | %+.1f | %.4f | %+.1f |" % (
            name, case, n, tau, product / r_cells, v, e, v_rc, e_rc))
        series.setdefault(box_of(name), []).append((n, e, e_rc))
        opening.append(("%s (%s, N = %g, tau %.3f), corrected: terminal speed" % (name, case, n, tau),
                        "u_inf %.3f m/s (unbounded)" % ten_cate_scenes.CASES[case]["u_inf"], "%.4f m/s" % v_rc, "%+.1f %%" % e_rc,
                        "python3 validation/imb/radius_correction.py %s" % name))
    text = ("# Ten Cate in larger boxes with the calibrated radius correction\n\n"
            + compact.summary(opening, "python3 validation/imb/radius_correction.py --report") + "\n\n"
            "Written by `python3 validation/imb/radius_correction.py --report` from "
            "`results/radius_correction.json` and `results/ten_cate.json` (runs on lavapipe, this repository's CPU "
            "machine). Each Ten Cate run (`ten_cate.py`) named in the first column run again with "
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
    ap.add_argument("runs", nargs="*", help="Ten Cate runs (larger boxes) by name, e.g. E3_N6_W200_H240")
    ap.add_argument("--report", action="store_true", help="only write the report from the results")
    ap.add_argument("--distil", metavar="DIR", help="distil DIR/<run>/ into the results, then write the report")
    ap.add_argument("--timeout", type=float, help="coupling.timeout [s] of the runs (default: the scene's)")
    args = ap.parse_args()
    if args.distil:
        distil([os.path.join(args.distil, name) for name in sorted(os.listdir(args.distil))])
    elif not args.report:
        for name in args.runs:
            if os.path.exists(os.path.join(OUT, name, "summary.json")) or name in compact.runs(SCRIPT):
                print("%s: already run, skipped" % name)
                continue
            print("%s: running" % name, flush=True)
            run(name, args.timeout)
    report()


if __name__ == "__main__":
    main()
