#!/usr/bin/env python3
"""The settling sphere's approach to the floor (Ten Cate et al. 2002, E1-E4) with and without the
squeeze film (`coupling.lubrication`, integrated in the DEM's sub-steps), every fluid step recorded.

    python3 validation/imb/approach.py run [N ...]     # runs missing (default N = 6)
    python3 validation/imb/approach.py report          # APPROACH.md and approach.png from results/approach.json
    python3 validation/imb/approach.py distil DIR      # DIR/<case>_N<n>_lub-<on|off>/ into results/approach.json

Scenes as validation/imb/ten_cate.py writes them (the experiment's 100 x 100 x 160 mm box, TRT,
Mach 0.1), with one row of particles.csv per fluid step and, for "off", `coupling.lubrication = false`.
Runs go to the ignored work folder validation/imb/work/approach/<case>_N<n>_lub-<on|off>/ (scene.toml,
summary.json, log.txt, particles.csv reduced to the sphere from 40 mm above the floor on); what the
report needs of each (its figures, and the sphere's time and height for the chart) is its record in
validation/imb/results/approach.json, from which the report is built.
"""

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import results as compact  # noqa: E402
import ten_cate_analysis  # noqa: E402  (validation/imb/ten_cate.py's parts: the log and the series read)
import ten_cate_charts  # noqa: E402  (the cases' colours)
import ten_cate_runs  # noqa: E402  (the binary and the csv reduction)
import ten_cate_scenes  # noqa: E402  (the cases, the sphere and the scene writer)

HERE = ten_cate_scenes.HERE
SCRIPT = "approach"
RUNS = compact.work(SCRIPT)
NAME_RE = re.compile(r"(E\d)_N([0-9p]+)_lub-(on|off)$")
KEEP_BELOW = 0.040       # m: rows kept once the gap is below this
SETTINGS = ("on", "off")
TIME_FACTOR = 1.6        # simulated time = TIME_FACTOR x 120 mm / u_inf (E4 needs more than ten_cate.py's 1.3 to settle)


def run_dir(case, n, lub):
    return os.path.join(RUNS, "%s_N%s_lub-%s" % (case, ten_cate_scenes.ntag(n), lub))


def write_scene(case, n, lub, path):
    ln = ten_cate_scenes.write_scene(case, n, path, sim_time=TIME_FACTOR * ten_cate_scenes.GAP0 / ten_cate_scenes.CASES[case]["u_inf"])
    text = open(path).read()
    text = re.sub(r"^interval = .*", "interval = 1                         # every fluid step", text, count=1, flags=re.M)
    text = re.sub(r'^name = "(.*)"', r'name = "\1-lub-%s"' % lub, text, count=1, flags=re.M)
    text = text.replace("\n[particles]\n", "\n[coupling]\nlubrication = %s\n\n[particles]\n"
                        % ("true" if lub == "on" else "false"), 1)
    open(path, "w").write(text)
    return ln


def run_one(case, n, lub):
    out = run_dir(case, n, lub)
    if os.path.exists(os.path.join(out, "summary.json")) or os.path.basename(out) in compact.runs(SCRIPT):
        print("%s N=%g lubrication %s: already run" % (case, n, lub))
        return
    os.makedirs(out, exist_ok=True)
    scene = os.path.join(out, "scene.toml")
    ln = write_scene(case, n, lub, scene)
    print("%s N=%g lubrication %s: %d steps" % (case, n, lub, ln["steps"]), flush=True)
    tmp = os.path.join("/tmp", "approach_" + os.path.basename(out))
    shutil.rmtree(tmp, ignore_errors=True)
    t0 = time.time()
    with open(os.path.join(out, "log.txt"), "w") as log:
        p = subprocess.run([ten_cate_runs.BINARY, "run", scene, "--out", tmp], stdout=log, stderr=subprocess.STDOUT,
                           env=dict(os.environ, NODEVICE_SELECT="1"), cwd=ten_cate_scenes.ROOT)
    print("  exit %d after %.1f s" % (p.returncode, time.time() - t0), flush=True)
    for name in ("summary.json",):
        if os.path.exists(os.path.join(tmp, name)):
            shutil.copy(os.path.join(tmp, name), os.path.join(out, name))
    if os.path.exists(os.path.join(tmp, "particles.csv")):
        ten_cate_runs.reduce_csv(os.path.join(tmp, "particles.csv"), os.path.join(out, "particles.csv"),
                      keep=("step", "time", "z", "vz", "fz"), digits=9,
                      row_kept=lambda row: float(row["z"]) - ten_cate_scenes.R < KEEP_BELOW)
    shutil.rmtree(tmp, ignore_errors=True)
    distil([out])


def at_crossing(y, gap, level):
    """y where the gap first falls to `level` (linear between rows), None if never."""
    for k in range(1, len(gap)):
        if gap[k] <= level < gap[k - 1]:
            f = (gap[k - 1] - level) / (gap[k - 1] - gap[k])
            return y[k - 1] + f * (y[k] - y[k - 1])
    return None


def film_alone_time(case, dx, h0, h1):
    """Quasi-steady closing time of the floor film alone from h0 to h1 under the buoyant weight F:
    K/F (ln(h0/h1) - (h0 - h1)/dx), K = 6 pi mu r^2."""
    c = ten_cate_scenes.CASES[case]
    weight = (ten_cate_scenes.RHO_P - c["rho_f"]) * math.pi / 6.0 * ten_cate_scenes.D ** 3 * 9.81
    k = 6.0 * math.pi * c["mu"] * ten_cate_scenes.R ** 2
    return k / weight * (math.log(h0 / h1) - (h0 - h1) / dx)


def analyse(out, case, n, lub):
    """The record of the run in folder OUT: the report's figures and the chart's series (None without
    particles.csv)."""
    p = os.path.join(out, "particles.csv")
    if not os.path.exists(p):
        return None
    d = ten_cate_analysis.load_series(p)
    t, gap, speed = d["time"], [z - ten_cate_scenes.R for z in d["z"]], [-v for v in d["vz"]]
    s = json.load(open(os.path.join(out, "summary.json")))
    info = ten_cate_analysis.parse_log(os.path.join(out, "log.txt"))
    log = open(os.path.join(out, "log.txt")).read()
    m = re.search(r"DEM step ([0-9.eE+-]+) s = fluid step / (\d+)", log)
    dx = ten_cate_scenes.D / n
    res = dict(case=case, N=n, lub=lub, dx=dx, dir=os.path.basename(out), exit_reason=s.get("exit_reason"),
               wall_time_s=s.get("wall_time_s"), tau=info.get("tau"), dt=info.get("dt"),
               dem_substeps=int(m.group(2)) if m else None,
               dem_physics=(s.get("peer") or {}).get("physics"), fluid_physics=s.get("fluid_physics"))
    t1 = at_crossing(t, gap, dx)
    res["t_1dx"] = t1
    for name, level in (("dx", dx), ("0p1dx", 0.1 * dx), ("0p01d", 0.01 * ten_cate_scenes.D)):
        tl = at_crossing(t, gap, level)
        res["dt_to_" + name] = None if tl is None or t1 is None else tl - t1
        res["speed_at_" + name] = at_crossing(speed, gap, level)
    res["film_ratio"] = {}
    for h0, h1 in ((0.5e-3, 0.1e-3), (0.2e-3, 0.1e-3)):
        t0, t1_ = at_crossing(t, gap, h0), at_crossing(t, gap, h1)
        if t0 is not None and t1_ is not None:
            res["film_ratio"]["%g-%g" % (h0 * 1e3, h1 * 1e3)] = (t1_ - t0) / film_alone_time(case, dx, h0, h1)
    first = next((k for k in range(len(gap)) if gap[k] <= 0.0), None)
    res["t_contact"] = t[first] if first is not None else None
    res["dt_to_contact"] = None if first is None or t1 is None else t[first] - t1
    after = gap[first:] if first is not None else []
    res["rebound_max_gap"] = max(after) if after else None
    # rms speed over the last third of the time after the first contact
    tail = [v for tk, v in zip(t, speed) if first is not None and tk >= t[-1] - (t[-1] - t[first]) / 3.0]
    res["rms_speed_end"] = (sum(v * v for v in tail) / len(tail)) ** 0.5 if tail else None
    res["final_gap"] = gap[-1]
    res["series"] = dict(t=t, z=d["z"])     # as particles.csv has them (9 digits): the chart's series
    return res


def distil(folders):
    """The records of the run FOLDERS (named <case>_N<n>_lub-<on|off>) into results/approach.json."""
    out = {}
    for folder in folders:
        name = os.path.basename(os.path.normpath(folder))
        m = NAME_RE.match(name)
        res = analyse(folder, m.group(1), float(m.group(2).replace("p", ".")), m.group(3)) if m else None
        if res is None:
            print("%s: no run, not distilled" % folder)
            continue
        out[name] = res
    compact.merge(SCRIPT, out, about="The settling sphere's approach to the floor: one record per run of "
                  "validation/imb/approach.py (its figures; the series t, z of the sphere, 9 digits, from 40 mm "
                  "above the floor on).")


def records():
    """The records of results/approach.json in the order of their names, the series as the chart reads
    them (t, gap)."""
    out = []
    for _, r in sorted(compact.runs(SCRIPT).items()):
        r = dict(r)
        r["series"] = dict(t=r["series"]["t"], gap=[z - ten_cate_scenes.R for z in r["series"]["z"]])
        out.append(r)
    return out


def chart(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cases = sorted({r["case"] for r in results})
    fig, axes = plt.subplots(1, len(cases), figsize=(4.2 * len(cases), 3.8), squeeze=False)
    for ax, case in zip(axes[0], cases):
        for r in (r for r in results if r["case"] == case):
            s = r["series"]
            t0 = r["t_1dx"] or 0.0
            style = "-" if r["lub"] == "on" else "--"
            ax.plot([x - t0 for x in s["t"]], [max(g, 1e-6) * 1e3 for g in s["gap"]], style,
                    color=ten_cate_charts.COLORS[case], alpha=1.0 if r["lub"] == "on" else 0.6,
                    label="N = %g, films %s" % (r["N"], r["lub"]))
        ax.axhline(ten_cate_scenes.D / min(r["N"] for r in results if r["case"] == case) * 1e3, color="0.6", lw=0.8, ls=":")
        ax.set_yscale("log")
        ax.set_xlim(-0.1, None)
        ax.set_ylim(1e-3, 40)
        ax.set_xlabel("t - t(gap = 1 cell) [s]")
        ax.set_title("%s (St %.2f)" % (case, ten_cate_scenes.CASES[case]["St"]))
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("gap to the floor [mm] (1 um shown for contact)")
    fig.suptitle("Approach to the floor with the squeeze film in the DEM (solid) and without (dashed); "
                 "dotted: one cell", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def fmt(v, f="%.3g"):
    return "-" if v is None else f % v


def summary_rows(results):
    """Per run with the films on: the closing time of the gap from 0.5 to 0.1 mm against the film alone's."""
    rows = []
    for r in sorted(results, key=lambda r: (r["case"], r["N"])):
        ratio = r["film_ratio"].get("0.5-0.1")
        if r["lub"] != "on" or ratio is None:
            continue
        alone = film_alone_time(r["case"], r["dx"], 0.5e-3, 0.1e-3)
        rows.append(("%s, N = %g, films on: time for the gap to close from 0.5 to 0.1 mm" % (r["case"], r["N"]),
                     "%.3g s, the quasi-steady film alone" % alone, "%.3g s" % (ratio * alone),
                     "%+.0f %%" % (100.0 * (ratio - 1.0)),
                     "python3 validation/imb/approach.py run %g --cases %s" % (r["N"], r["case"])))
    return rows


def report(results):
    lines = [
        "# The settling sphere's approach to the floor, with and without the squeeze film",
        "",
        compact.summary(summary_rows(results), "python3 validation/imb/approach.py report"),
        "",
        "Generated by `python3 validation/imb/approach.py report` from `results/approach.json`. **Device: a CPU** "
        "(Mesa lavapipe, 2 shared cores; no GPU in this session).",
        "",
        "Ten Cate et al. (2002) E1-E4 as in `validation/imb/REPORT.md` (the experiment's 100 x 100 x 160 mm "
        "box, TRT, Mach 0.1, sphere released with its bottom 120 mm above the floor), recorded at every fluid "
        "step once the gap is below 40 mm. **films on**: `coupling.lubrication = true` (the default): the DEM "
        "integrates the squeeze film F = 6 pi mu r^2 (1/h - 1/dx) v_n against the floor in its sub-steps for "
        "gaps below one cell (docs/imb.md). **films off**: `coupling.lubrication = false`. Everything else "
        "(sub-step drag on) the same. The lattice resolves the gap down to about one cell either way; the "
        "film acts only below it. Ten Cate et al.'s measured trajectories are not in ../shared, so this "
        "compares the two settings, not the experiment.",
        "",
        "Columns: times from the moment the gap is one cell (dx = 15 mm / N); speeds (downward) where the "
        "gap crosses the level; contact = first fluid step with the gap <= 0; rebound = largest gap after "
        "the first contact (negative: it never lifts off); final gap at the end of the run (1.6 x 120 mm / u_inf "
        "simulated); rms speed over the last third of the time after the first contact.",
        "",
        "| case | N | films | dx [mm] | t to 0.1 dx [s] | t to 0.01 d [s] | t to contact [s] | speed at 1 dx [m/s] | "
        "speed at 0.1 dx [m/s] | speed at 0.01 d [m/s] | rebound [um] | final gap [um] | rms speed at the end [m/s] | "
        "DEM steps per fluid step | wall time [s] | run |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(results, key=lambda r: (r["case"], r["N"], r["lub"] != "on")):
        lines.append("| %s | %g | %s | %.3g | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | `%s` |" % (
            r["case"], r["N"], r["lub"], r["dx"] * 1e3, fmt(r["dt_to_0p1dx"]), fmt(r["dt_to_0p01d"]),
            fmt(r["dt_to_contact"]), fmt(r["speed_at_dx"]), fmt(r["speed_at_0p1dx"]), fmt(r["speed_at_0p01d"]),
            fmt(None if r["rebound_max_gap"] is None else r["rebound_max_gap"] * 1e6, "%.2f"),
            fmt(r["final_gap"] * 1e6, "%.2f"), fmt(r["rms_speed_end"], "%.2e"), fmt(r["dem_substeps"], "%d"),
            fmt(r["wall_time_s"], "%.0f"), r["dir"]))
    lines += ["", "Closing time of the last gap against the quasi-steady film alone, K/F (ln(h0/h1) - (h0 - h1)/dx), "
              "K = 6 pi mu r^2, F the buoyant weight (1 = the film carries the whole weight at every instant):", "",
              "| case | N | films | 0.5 -> 0.1 mm | 0.2 -> 0.1 mm |", "|---|---|---|---|---|"]
    for r in sorted(results, key=lambda r: (r["case"], r["N"])):
        if r["lub"] == "on":
            fr = r["film_ratio"]
            lines.append("| %s | %g | on | %s | %s |" % (r["case"], r["N"], fmt(fr.get("0.5-0.1"), "%.2f"),
                                                         fmt(fr.get("0.2-0.1"), "%.2f")))
    lines += ["", "![approach](approach.png)", ""]
    findings = os.path.join(HERE, "approach_findings.md")
    if os.path.exists(findings):
        lines += [open(findings).read().rstrip(), ""]
    open(os.path.join(HERE, "APPROACH.md"), "w").write("\n".join(lines))


def main():
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = a.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("N", nargs="*", type=float, default=[6.0])
    r.add_argument("--cases", nargs="+", default=list(ten_cate_scenes.CASES), choices=list(ten_cate_scenes.CASES))
    sub.add_parser("report")
    d = sub.add_parser("distil")
    d.add_argument("dir")
    args = a.parse_args()
    if args.cmd == "run":
        for n in args.N:
            for case in args.cases:
                for lub in SETTINGS:
                    run_one(case, n, lub)
        return
    if args.cmd == "distil":
        distil([os.path.join(args.dir, name) for name in sorted(os.listdir(args.dir))])
    results = records()
    if not results:
        raise SystemExit("no runs in %s" % compact.path(SCRIPT))
    chart(results, os.path.join(HERE, "approach.png"))
    report(results)
    print("wrote APPROACH.md, approach.png (%d runs)" % len(results))


if __name__ == "__main__":
    main()
