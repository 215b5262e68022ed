#!/usr/bin/env python3
"""Ten Cate et al. (2002) case E1 against the experiment itself: the measured velocity and gap over
time (reference/ten_cate_2002_E1_*.csv, digitized from the paper's figures), not only u_inf.

The runs are the experiment's: the closed 100 x 100 x 160 mm box, the sphere released from rest
with its bottom 120 mm above the floor (scenes from validation/imb/ten_cate_scenes.py's `write_scene`),
TRT, Mach 0.05 by default (tau 0.85 / 1.03 / 1.20 at 6 / 9 / 12 cells per diameter: at Mach 0.1
E1's tau is 1.2-2.25, which biases the boundary: REPORT.md, "Tau check"; `--mach` for a series at
one tau), with the code of the day they were run. The runs are made in the ignored work folder
validation/imb/work/experiment/<run>/; what the report needs of each (its lattice, tau, device and the
sphere's time, height and vertical velocity) is its record in validation/imb/results/experiment.json,
from which the report and the chart are built.

    python3 validation/imb/experiment.py run 6 9 12     # run the missing resolutions, then report
    python3 validation/imb/experiment.py run 12 --mach 0.0375   # N = 12 at tau 1.03 (as N = 9 at Mach 0.05)
    python3 validation/imb/experiment.py report         # EXPERIMENT.md and experiment_E1.png from the results
    python3 validation/imb/experiment.py scenes DIR 15 --mach 0.03    # DIR/exp_E1_N15_M0p03/scene.toml, a plan line
    python3 validation/imb/experiment.py import DIR     # DIR/exp_<run>/ (lbm-server's outputs) into the results
    python3 validation/imb/experiment.py distil DIR     # DIR/<run>/ (folders as `run` leaves them) into the results

`scenes` and `import` are for the GPU batch (validation/gpu/prepare.sh, run.sh, import.sh): the
experiment's box is a whole number of cells at 15, 24 and 30 cells per diameter (dx must divide
100 and 160 mm); 24 cells would take lavapipe some 3 hours, 30 cells 10.
"""
import argparse
import csv
import json
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import results as compact  # noqa: E402
import ten_cate_analysis  # noqa: E402  (validation/imb/ten_cate.py's parts: the log and the series read)
import ten_cate_runs  # noqa: E402  (a run made, a batch's runs imported)
import ten_cate_scenes  # noqa: E402  (the cases, the sphere and the scene writer)

SCRIPT = "experiment"
RUNS = compact.work(SCRIPT)
REFERENCE = os.path.join(HERE, "reference")
CASE = "E1"
MACH = 0.05
SIM_TIME = 4.5       # s: the experiment's curves end at 4.1 s, the sphere on the floor
GAPS = (6.0, 4.0, 2.0, 1.0, 0.5)   # gaps / d at which the times are compared
WINDOW = (1.7, 2.5)  # s: the measured plateau (the speed's points there all but equal)


def read_reference(name):
    """Columns of a reference csv (lines starting with # are its provenance)."""
    with open(os.path.join(REFERENCE, name)) as f:
        rows = [l for l in f if not l.startswith("#")]
    r = csv.reader(rows)
    next(r)
    cols = list(zip(*[[float(v) for v in row] for row in r if row]))
    return [list(c) for c in cols]


def run_dir(n, mach=MACH):
    return os.path.join(RUNS, "%s_N%s_M%s" % (CASE, ten_cate_scenes.ntag(n), ten_cate_scenes.ntag(mach)))


PREFIX = "exp_"       # the batch's scene folders: exp_<run folder name>


def write_scenes(folder, ns, mach=MACH, sim_time=SIM_TIME):
    """The scenes of `run` without running them: FOLDER/exp_<run>/scene.toml, a plan line each on
    stdout (name, cells, tau, steps, cell-steps) for the batch script."""
    for n in ns:
        name = PREFIX + os.path.basename(run_dir(n, mach))
        os.makedirs(os.path.join(folder, name), exist_ok=True)
        ln = ten_cate_scenes.write_scene(CASE, n, os.path.join(folder, name, "scene.toml"), mach=mach, sim_time=sim_time)
        cells = ln["cells"][0] * ln["cells"][1] * ln["cells"][2]
        print("%s %dx%dx%d tau %.3f steps %d cell-steps %.3g" % (name, *ln["cells"], ln["tau"], ln["steps"],
                                                                 cells * ln["steps"]))


def import_runs(src):
    """Each SRC/exp_<run>/ with a summary.json into the work folder (`ten_cate_runs.import_runs`), then into
    the results."""
    distil(ten_cate_runs.import_runs(src, force=True, runs=RUNS, prefix=PREFIX))


def run(n, mach=MACH, force=False):
    out = run_dir(n, mach)
    if os.path.basename(out) in compact.runs(SCRIPT) and not force:
        print("%s: already run, skipped" % os.path.basename(out))
        return
    ten_cate_runs.run_one(CASE, n, force, mach, sim_time=SIM_TIME, out=out)
    distil([out])


def distil(folders):
    """The records of the run FOLDERS (E1_N<n>_M<mach>, with particles.csv) into the results."""
    out = {}
    for folder in folders:
        if not os.path.exists(os.path.join(folder, "particles.csv")):
            print("%s: no particles.csv, not distilled" % folder)
            continue
        s = ten_cate_analysis.load_series(os.path.join(folder, "particles.csv"))
        info = ten_cate_analysis.parse_log(os.path.join(folder, "log.txt"))
        name = os.path.basename(os.path.normpath(folder))
        summary = os.path.join(folder, "summary.json")
        code = json.load(open(summary)).get("exit_code") if os.path.exists(summary) else None
        out[name] = dict(tau=info.get("tau"), cells=info.get("cells"), device=info.get("adapter", "?"), exit_code=code,
                         series=dict(t=s["time"], z=s["z"], vz=s["vz"]))
    compact.merge(SCRIPT, out, about="Ten Cate E1 against the experiment: one record per run of "
                  "validation/imb/experiment.py (tau, lattice, device from its log; the exit code; the series t, z, "
                  "vz of the sphere as its reduced particles.csv has them, 7 digits).")


def interp(x, xs, ys):
    """Linear interpolation of (xs, ys) at x (xs increasing); None outside."""
    if x < xs[0] or x > xs[-1]:
        return None
    for k in range(1, len(xs)):
        if xs[k] >= x:
            f = (x - xs[k - 1]) / (xs[k] - xs[k - 1]) if xs[k] > xs[k - 1] else 0.0
            return ys[k - 1] + f * (ys[k] - ys[k - 1])
    return ys[-1]


def time_at_gap(g, ts, gaps):
    """First time the gap (decreasing on the whole) comes down to g, interpolated; None if never."""
    for k in range(1, len(ts)):
        if gaps[k - 1] >= g >= gaps[k] and gaps[k - 1] > gaps[k]:
            return ts[k - 1] + (gaps[k - 1] - g) / (gaps[k - 1] - gaps[k]) * (ts[k] - ts[k - 1])
    return None


def gap_from_speed(exp_v):
    """The gap / d the measured speed gives, integrated by the trapezoid rule from rest at the
    release gap at t = 0 (the curve's repeated first point taken once)."""
    tv, vz = exp_v
    ts, vs = [0.0], [0.0]
    for t, v in zip(tv, vz):
        if t > ts[-1]:
            ts.append(t)
            vs.append(-v)
    gaps = [ten_cate_scenes.GAP0 / ten_cate_scenes.D]
    for k in range(1, len(ts)):
        gaps.append(gaps[-1] - 0.5 * (vs[k] + vs[k - 1]) * (ts[k] - ts[k - 1]) / ten_cate_scenes.D)
    return ts, gaps


def load_run(out, r):
    """The run OUT (its name) from its record R: its series as the report reads them."""
    s = r["series"]
    t = s["t"]
    speed = [-v for v in s["vz"]]
    gap = [(z - ten_cate_scenes.R) / ten_cate_scenes.D for z in s["z"]]
    n = float(os.path.basename(out).split("_N")[1].split("_M")[0].replace("p", "."))
    mach = float(os.path.basename(out).split("_M")[1].replace("p", "."))
    return dict(n=n, mach=mach, t=t, speed=speed, gap=gap, tau=r["tau"], cells=r["cells"], dir=out,
                device=r["device"])


def compare(r, exp_v, exp_g):
    """The run against the experiment: peak speed, speed over the experiment's points, gap times."""
    (tv, vz), (tg, gd) = exp_v, exp_g
    exp_speed = [-v for v in vz]
    peak = max(r["speed"])
    t_peak = r["t"][r["speed"].index(peak)]
    # The measured plateau: the speed's points in WINDOW (five of them at the same digitized value),
    # and the slope of the measured gap there (least squares).
    plateau = [s for t, s in zip(tv, exp_speed) if WINDOW[0] <= t <= WINDOW[1]]
    pts = [(t, g * ten_cate_scenes.D) for t, g in zip(tg, gd) if WINDOW[0] <= t <= WINDOW[1]]
    mt, mg = sum(p[0] for p in pts) / len(pts), sum(p[1] for p in pts) / len(pts)
    slope = -sum((t - mt) * (g - mg) for t, g in pts) / sum((t - mt) ** 2 for t, _ in pts)
    inside = [v for t, v in zip(r["t"], r["speed"]) if WINDOW[0] <= t <= WINDOW[1]]
    diffs = []
    for t, s in zip(tv, exp_speed):
        ours = interp(t, r["t"], r["speed"])
        if ours is not None and t <= 3.0:      # before the floor decelerates the sphere
            diffs.append(ours - s)
    rms = math.sqrt(sum(d * d for d in diffs) / len(diffs))
    mean = sum(diffs) / len(diffs)
    ti, gi = gap_from_speed(exp_v)
    times = {g: (time_at_gap(g, r["t"], r["gap"]), time_at_gap(g, tg, gd), time_at_gap(g, ti, gi)) for g in GAPS}
    return dict(peak=peak, t_peak=t_peak, exp_peak=max(exp_speed), exp_plateau=sum(plateau) / len(plateau),
                plateau=sum(inside) / len(inside), exp_slope=slope, slope_points=len(pts),
                rms=rms, mean=mean, points=len(diffs), times=times)


def chart(runs, exp_v, exp_g, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5))
    (tv, vz), (tg, gd) = exp_v, exp_g
    a1.plot(tv, [-v for v in vz], "ks", ms=4, label="experiment (Ten Cate et al. 2002)")
    a2.plot(tg, gd, "ks", ms=4, label="experiment")
    ti, gi = gap_from_speed(exp_v)
    a2.plot(ti, gi, "k:", label="the measured speed integrated")
    for r in runs:
        lab = "N = %g, Mach %g (tau %.2f)" % (r["n"], r["mach"], r["tau"] or float("nan"))
        a1.plot(r["t"], r["speed"], "-", label=lab)
        a2.plot(r["t"], r["gap"], "-", label=lab)
    a1.axhline(ten_cate_scenes.CASES[CASE]["u_inf"], color="grey", ls=":", label="u_inf (unbounded)")
    a1.set_xlabel("t [s]")
    a1.set_ylabel("settling speed -v_z [m/s]")
    a1.set_title("E1 (Re 1.5) in the experiment's box: speed")
    a2.set_xlabel("t [s]")
    a2.set_ylabel("gap / d (bottom of the sphere to the floor)")
    a2.set_title("E1: gap")
    for a in (a1, a2):
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def pct(a, b):
    return 100.0 * (a - b) / b


def report():
    exp_v = read_reference("ten_cate_2002_E1_velocity.csv")
    exp_g = read_reference("ten_cate_2002_E1_gap.csv")
    every = sorted((load_run(d, r) for d, r in compact.runs(SCRIPT).items()), key=lambda r: (-r["mach"], r["n"]))
    # A run compared simulated the measured plateau and the first 3 s (a run stopped early did not).
    runs = [r for r in every if r["t"] and r["t"][-1] >= 3.0]
    short = ["%s (%.2f s simulated)" % (os.path.basename(r["dir"]), r["t"][-1] if r["t"] else 0.0)
             for r in every if r not in runs]
    chart(runs, exp_v, exp_g, os.path.join(HERE, "experiment_E1.png"))
    rows, times, opening = comparison_rows(runs, exp_v, exp_g)
    c0 = compare(runs[0], exp_v, exp_g) if runs else None
    ti, gi = gap_from_speed(exp_v)
    at = 2.44
    drift = (interp(at, *exp_g), interp(at, ti, gi))
    text = EXPERIMENT_REPORT % dict(opening=compact.summary(opening, "python3 validation/imb/experiment.py report"), mach=MACH, sim=SIM_TIME, exp_peak=c0["exp_peak"] if c0 else float("nan"),
        exp_plateau=c0["exp_plateau"] if c0 else float("nan"), rows="\n".join(rows),
        at=at, g_meas=drift[0], g_speed=drift[1], w0=WINDOW[0], w1=WINDOW[1],
        exp_slope=c0["exp_slope"] if c0 else float("nan"), slope_points=c0["slope_points"] if c0 else 0,
        gap_heads=" | ".join("gap %g d" % g for g in GAPS), gap_bars="---|" * len(GAPS), times="\n".join(times),
        u_inf=ten_cate_scenes.CASES[CASE]["u_inf"],
        plateau_vs_uinf=pct(c0["exp_plateau"], ten_cate_scenes.CASES[CASE]["u_inf"]) if c0 else float("nan"),
        short="\n\nNot compared (shorter than 3 s of fall): " + ", ".join(short) + "." if short else "")
    with open(os.path.join(HERE, "EXPERIMENT.md"), "w") as f:
        f.write(text)
    print(text)


def comparison_rows(runs, exp_v, exp_g):
    """The rows of the speed and gap tables of each run compared, and its row of the summary."""
    rows, times, opening = [], [], []
    for r in runs:
        c = compare(r, exp_v, exp_g)
        opening.append(("E1, N = %g, Mach %g (tau %.2f): plateau speed, %g-%g s" % (r["n"], r["mach"], r["tau"] or float("nan"),
                                                                                WINDOW[0], WINDOW[1]),
                        "%.4f m/s, measured" % c["exp_plateau"], "%.4f m/s" % c["plateau"],
                        "%+.1f %%" % pct(c["plateau"], c["exp_plateau"]),
                        "python3 validation/imb/experiment.py run %g --mach %g" % (r["n"], r["mach"])))
        rows.append("| %g | %g | %s | %.3f | %.4f at %.2f s | %.4f | %+.1f | %+.1f | %.2f / %+.2f (%d points) | %s |"
                    % (r["n"], r["mach"], "x".join(map(str, r["cells"] or [])), r["tau"] or float("nan"), c["peak"], c["t_peak"],
                       c["plateau"], pct(c["plateau"], c["exp_plateau"]), pct(c["plateau"], c["exp_slope"]),
                       1e3 * c["rms"], 1e3 * c["mean"], c["points"], r["device"]))
        times.append("| %g | %g | %s |" % (r["n"], r["mach"], " | ".join(gap_cells(c))))
    return rows, times, opening


def gap_cells(c):
    """The gap table's cells of the comparison C: the simulated time to each gap, against the measured gap and
    the measured speed integrated."""
    cells = []
    for g in GAPS:
        ours, exp, by_speed = c["times"][g]
        rel = lambda ref: "-" if ours is None or ref is None else "%.2f (%+.1f%%)" % (ref, pct(ours, ref))
        cells.append("-" if ours is None else "%.2f / %s / %s" % (ours, rel(exp), rel(by_speed)))
    return cells


EXPERIMENT_REPORT = """# Ten Cate et al. (2002) E1 against the experiment's own curves (issue 5)

%(opening)s

Generated by `python3 validation/imb/experiment.py report` from `results/experiment.json` (runs
made by `experiment.py run N...`). REPORT.md compares every case with u_inf,
the unbounded terminal velocity; here E1 (Re 1.5, the case the experiment's walls slow most) is
compared with what the experiment measured in its box: the sphere's speed and its gap to the floor
over time, digitized from the paper's figures (`reference/ten_cate_2002_E1_velocity.csv` and
`_gap.csv`, with their provenance; the other cases' curves are not in the reference files).

Set-up: the experiment's closed 100 x 100 x 160 mm box, the sphere (d = 15 mm, 1120 kg/m^3)
released from rest with its bottom 120 mm above the floor, fluid 970 kg/m^3 and 0.373 Pa s, TRT,
the Mach number of u_inf and tau in the tables (tau 1.03 at every N in one series: the boundary's
effective size depends on tau, REPORT.md "Tau check"), lubrication and the sub-step drag as by
default, %(sim)g s simulated. The measured speed is digitized in steps of about 0.3 mm/s (1%% of the speed): its peak
%(exp_peak).4f m/s is a single point at 1.56 s, its plateau %(exp_plateau).4f m/s the mean of the
points from 1.7 to 2.5 s. **The two measured curves disagree with each other**: integrated from
rest, the measured speed puts the sphere at %(g_speed).2f d above the floor at %(at)g s where the
measured gap reads %(g_meas).2f d, and on the floor by about 3.4 s where the gap curve still reads
0.6 d (between 1.56 and 2.44 s the gap falls at 0.0358 m/s while the speed reads 0.0376 m/s). So a
run that follows one curve misses the other by up to 12%% in time; the gap table gives the
simulated time against both (the measured gap, and the measured speed integrated: the dotted line
in the chart), and the speed table the plateau against both: neither curve alone is the
reference to within 5%%.

![E1 against the experiment](experiment_E1.png)

## Speed

Plateau: the mean speed from %(w0)g to %(w1)g s. Against the measured speed there (%(exp_plateau).4f m/s)
and against the measured gap's slope there (%(exp_slope).4f m/s, least squares over its %(slope_points)d points):

| N (cells per d) | Mach | lattice | tau | peak speed [m/s] | plateau [m/s] | vs measured speed [%%] | vs measured gap's slope [%%] | speed - measured speed, rms / mean over t <= 3 s [mm/s] | device |
|---|---|---|---|---|---|---|---|---|---|
%(rows)s

## Gap: time to reach it (s: simulated / measured gap (error) / measured speed integrated (error))

| N | Mach | %(gap_heads)s |
|---|---|%(gap_bars)s
%(times)s

u_inf = %(u_inf)g m/s; the measured plateau is %(plateau_vs_uinf)+.1f%% from it (the walls of the
box).%(short)s
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("run")
    a.add_argument("N", type=float, nargs="+", help="cells per diameter")
    a.add_argument("--mach", type=float, default=MACH, help="Mach number of u_inf (default %g)" % MACH)
    a.add_argument("--force", action="store_true")
    sub.add_parser("report")
    sc = sub.add_parser("scenes")
    sc.add_argument("dir")
    sc.add_argument("N", type=float, nargs="+")
    sc.add_argument("--mach", type=float, default=MACH)
    sc.add_argument("--sim-time", type=float, default=SIM_TIME)
    im = sub.add_parser("import")
    im.add_argument("dir")
    di = sub.add_parser("distil")
    di.add_argument("dir")
    args = ap.parse_args()
    if args.cmd == "scenes":
        write_scenes(args.dir, args.N, args.mach, args.sim_time)
        return
    if args.cmd == "import":
        import_runs(args.dir)
    if args.cmd == "distil":
        distil([os.path.join(args.dir, d) for d in sorted(os.listdir(args.dir))])
    if args.cmd == "run":
        for n in args.N:
            run(n, args.mach, args.force)
    report()


if __name__ == "__main__":
    main()
