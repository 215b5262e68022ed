#!/usr/bin/env python3
"""Ten Cate et al. (2002) settling sphere, cases E1-E4, with the immersed moving boundary (issue 5).

For each case and each resolution (cells per diameter N, dx = 15 mm / N) this script writes a scene
derived from validation/scenes/ten-cate-e1.toml, runs `lbm-server run` (which starts dem-client), keeps
a reduced particles.csv, the summary.json and the log under validation/imb/runs/<case>_N<n>/, and then
writes results.json, REPORT.md and the charts in validation/imb/.

    python3 validation/imb/ten_cate.py run 3 6 7.5          # run the missing (case, N) pairs, then report
    python3 validation/imb/ten_cate.py run 6 --cases E1 E4  # a subset
    python3 validation/imb/ten_cate.py report               # only rebuild results/report/charts from runs/

Geometry: sphere d = 15 mm, rho_p = 1120 kg/m^3, closed box 100 x 100 x 160 mm, released from rest
with its *bottom* 120 mm above the floor (centre at z = 127.5 mm). Fluid properties and u_inf from
/work/shared/reference/ten-cate-2002.md. lattice.velocity_scale = u_inf, mach = 0.1, TRT, so
dt = 0.1/sqrt(3) dx / u_inf. Simulated time: 1.3 * 120 mm / u_inf (the sphere reaches the floor
region in every case: it settles slower than u_inf in the box).
"""
import argparse
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
TEMPLATE = os.path.join(ROOT, "validation", "scenes", "ten-cate-e1.toml")
BINARY = os.path.join(ROOT, "target", "release", "lbm-server")
RUNS = os.path.join(HERE, "runs")

D = 0.015            # m
R = D / 2
RHO_P = 1120.0       # kg/m^3
Z0 = 0.1275          # m, centre at release (bottom 120 mm above the floor)
GAP0 = Z0 - R        # 0.120 m
BOX = (0.1, 0.1, 0.16)
MACH = 0.1
TIME_FACTOR = 1.3

# Ten Cate et al. 2002, Table (reference file): rho_f, mu_f, u_inf (unbounded terminal velocity)
CASES = {
    "E1": dict(rho_f=970.0, mu=0.373, u_inf=0.038, Re=1.5, St=0.19),
    "E2": dict(rho_f=965.0, mu=0.212, u_inf=0.060, Re=4.1, St=0.53),
    "E3": dict(rho_f=962.0, mu=0.113, u_inf=0.091, Re=11.6, St=1.5),
    "E4": dict(rho_f=960.0, mu=0.058, u_inf=0.128, Re=32.2, St=4.1),
}
COLORS = {"E1": "tab:blue", "E2": "tab:orange", "E3": "tab:green", "E4": "tab:red"}
DEVICE = "CPU: Mesa lavapipe (llvmpipe) Vulkan, 2 shared cores; no GPU in this session"


def ntag(n):
    return ("%g" % n).replace(".", "p")


def run_dir(case, n, mach=MACH):
    """runs/<case>_N<n>, or runs/<case>_N<n>_M<mach> for a Mach number other than the default."""
    tail = "" if mach == MACH else "_M%s" % ntag(mach)
    return os.path.join(RUNS, "%s_N%s%s" % (case, ntag(n), tail))


def lattice_numbers(case, n, mach=MACH):
    c = CASES[case]
    dx = D / n
    for L in BOX:
        cells = L / dx
        if abs(cells - round(cells)) > 1e-6:
            raise SystemExit("N = %g: dx = %g m does not divide the box side %g m" % (n, dx, L))
    dt = mach / math.sqrt(3.0) * dx / c["u_inf"]
    nu = c["mu"] / c["rho_f"]
    tau = 0.5 + 3.0 * nu * dt / dx ** 2
    t_end = TIME_FACTOR * GAP0 / c["u_inf"]
    steps = int(math.ceil(t_end / dt))
    cells = [int(round(L / dx)) for L in BOX]
    return dict(dx=dx, dt=dt, tau=tau, nu=nu, t_end=t_end, steps=steps, cells=cells)


def sub1(pattern, repl, text):
    new, k = re.subn(pattern, repl, text, count=1, flags=re.M)
    if k != 1:
        raise SystemExit("template %s: no match for %r" % (TEMPLATE, pattern))
    return new


def write_scene(case, n, path, mach=MACH):
    c = CASES[case]
    ln = lattice_numbers(case, n, mach)
    text = open(TEMPLATE).read()
    text = sub1(r'^name = ".*"', 'name = "ten-cate-%s-N%s%s"' % (case.lower(), ntag(n), "" if mach == MACH else "-M" + ntag(mach)), text)
    text = sub1(r"^density = .*# kg/m\^3\n(?=dynamic_viscosity)", "density = %r                      # kg/m^3\n" % c["rho_f"], text)
    text = sub1(r"^dynamic_viscosity = .*", "dynamic_viscosity = %r                # Pa s" % c["mu"], text)
    text = sub1(r"^steps = .*", "steps = %d                          # %.4g s simulated" % (ln["steps"], ln["steps"] * ln["dt"]), text)
    text = sub1(r"^dx = .*", "dx = %r                           # m: %g cells per diameter" % (ln["dx"], n), text)
    text = sub1(r'^operator = .*', 'operator = "trt"', text)
    text = sub1(r"^velocity_scale = .*", "velocity_scale = %r               # m/s: u_inf of %s" % (c["u_inf"], case), text)
    text = sub1(r"^mach = .*", "mach = %r" % mach, text)
    interval = max(1, ln["steps"] // 300)
    text = sub1(r"^\[output\]\ninterval = .*",
                "[output]\ninterval = %d                         # steps between rows of particles.csv\n"
                "fields_interval = 0                  # last step's snapshot only (deleted after the run)" % interval, text)
    text = sub1(r"^density = 1120\.0.*", "density = %r                     # kg/m^3" % RHO_P, text)
    text = sub1(r"^position = .*", "position = [0.05, 0.05, %r]      # m: bottom 120 mm above the floor" % Z0, text)
    text = sub1(r"^radius = .*", "radius = %r                      # m" % R, text)
    text = text[text.index("name = "):]          # drop the template's E1 header comment
    text = ("# Ten Cate et al. 2002, case %s (Re %.1f, u_inf %.3f m/s), %g cells per diameter; generated by\n"
            "# validation/imb/ten_cate.py from validation/scenes/ten-cate-e1.toml\n" % (case, c["Re"], c["u_inf"], n)) + text
    with open(path, "w") as f:
        f.write(text)
    return ln


def reduce_csv(src, dst):
    keep = ["step", "time", "x", "y", "z", "vx", "vy", "vz", "fz"]
    with open(src) as f, open(dst, "w", newline="") as g:
        r = csv.DictReader(f)
        w = csv.writer(g)
        w.writerow(keep)
        for row in r:
            if row["id"] != "0":
                continue
            w.writerow([row["step"]] + ["%.7g" % float(row[k]) for k in keep[1:]])


def run_one(case, n, force=False, mach=MACH):
    out = run_dir(case, n, mach)
    if os.path.exists(os.path.join(out, "summary.json")) and not force:
        print("%s N=%g: already run (%s), skipped" % (case, n, out))
        return
    os.makedirs(out, exist_ok=True)
    scene = os.path.join(out, "scene.toml")
    ln = write_scene(case, n, scene, mach)
    print("%s N=%g: %d x %d x %d cells, dx %.4g m, dt %.4g s, tau %.4f (predicted), %d steps, %.3g s simulated"
          % (case, n, *ln["cells"], ln["dx"], ln["dt"], ln["tau"], ln["steps"], ln["steps"] * ln["dt"]), flush=True)
    if ln["tau"] < 0.5005:
        print("  tau %.5f < 0.5005: skipped" % ln["tau"])
        return
    tmp = os.path.join("/tmp", "ten_cate_" + os.path.basename(out))
    shutil.rmtree(tmp, ignore_errors=True)
    env = dict(os.environ, NODEVICE_SELECT="1")
    t0 = time.time()
    with open(os.path.join(out, "log.txt"), "w") as log:
        p = subprocess.run([BINARY, "run", scene, "--out", tmp], stdout=log, stderr=subprocess.STDOUT, env=env, cwd=ROOT)
    wall = time.time() - t0
    print("  exit %d after %.1f s" % (p.returncode, wall), flush=True)
    if os.path.exists(os.path.join(tmp, "summary.json")):
        shutil.copy(os.path.join(tmp, "summary.json"), os.path.join(out, "summary.json"))
    if os.path.exists(os.path.join(tmp, "particles.csv")):
        reduce_csv(os.path.join(tmp, "particles.csv"), os.path.join(out, "particles.csv"))
    shutil.rmtree(tmp, ignore_errors=True)   # drops fields/ (.vti) and the full csv


def parse_log(path):
    """tau, dt, dx, cells, adapter from lbm-server's first line."""
    info = {}
    if not os.path.exists(path):
        return info
    text = open(path).read()
    m = re.search(r"lattice (\d+)x(\d+)x(\d+) \((\w+), tau ([0-9.eE+-]+), dx ([0-9.eE+-]+) m, dt ([0-9.eE+-]+) s\) on (.*?), immersed", text)
    if m:
        info.update(cells=[int(m.group(i)) for i in (1, 2, 3)], operator=m.group(4), tau=float(m.group(5)),
                    dx=float(m.group(6)), dt=float(m.group(7)), adapter=m.group(8))
    m = re.search(r"DEM step ([0-9.eE+-]+) s = fluid step / (\d+)", text)
    if m:
        info["dem_substeps"] = int(m.group(2))
    errs = [l for l in text.splitlines() if "error" in l.lower()]
    if errs:
        info["errors"] = errs[:5]
    return info


def load_series(path):
    cols = {}
    with open(path) as f:
        r = csv.DictReader(f)
        for row in r:
            for k, v in row.items():
                cols.setdefault(k, []).append(float(v))
    return cols


def analyse(case, n, mach=MACH):
    out = run_dir(case, n, mach)
    sp = os.path.join(out, "summary.json")
    if not os.path.exists(sp):
        return None
    s = json.load(open(sp))
    c = CASES[case]
    ln = lattice_numbers(case, n, mach)
    info = parse_log(os.path.join(out, "log.txt"))
    dt = info.get("dt", ln["dt"])
    res = dict(case=case, N=n, mach=mach, dx=ln["dx"], cells=info.get("cells", ln["cells"]), dt=dt,
               tau=info.get("tau"), tau_predicted=ln["tau"], u_inf=c["u_inf"], Re_inf=c["Re"],
               steps=s.get("steps_completed"), steps_requested=s.get("steps_requested"),
               exit_reason=s.get("exit_reason"), exit_code=s.get("exit_code"),
               wall_time_s=s.get("wall_time_s"), adapter=info.get("adapter"), device=DEVICE,
               dem_substeps=info.get("dem_substeps"))
    if "errors" in info:
        res["log_errors"] = info["errors"]
    pp = os.path.join(out, "particles.csv")
    if os.path.exists(pp):
        d = load_series(pp)
        t, z, vz = d["time"], d["z"], d["vz"]
        speed = [-v for v in vz]                       # settling speed, downward positive
        i = max(range(len(speed)), key=lambda k: speed[k])
        sim_t = res["steps"] * dt if res["steps"] else t[-1]
        res.update(peak_speed=speed[i], peak_time=t[i], peak_gap=z[i] - R,
                   peak_error_pct=100.0 * (speed[i] - c["u_inf"]) / c["u_inf"],
                   simulated_time_s=sim_t, final_gap=z[-1] - R,
                   wall_s_per_sim_s=(res["wall_time_s"] / sim_t) if sim_t > 0 else None,
                   mlups=(ln["cells"][0] * ln["cells"][1] * ln["cells"][2] * res["steps"] / res["wall_time_s"] / 1e6)
                   if res["steps"] else None,
                   Re_peak=c["rho_f"] * speed[i] * D / c["mu"])
        # time for the gap to close from 120 mm to 1 d (15 mm) and to 0.1 d
        for lim, key in ((D, "t_gap_1d"), (0.1 * D, "t_gap_0p1d")):
            hit = next((t[k] for k in range(len(z)) if z[k] - R <= lim), None)
            res[key] = hit
        # mean speed while the gap closes from 80 to 40 mm (smooths the ripple of coarse grids)
        band = [speed[k] for k in range(len(z)) if 0.040 <= z[k] - R <= 0.080]
        res["plateau_speed"] = sum(band) / len(band) if band else None
        # after landing (gap < 0.5 mm for the last quarter of the run): rms of the reported velocity
        # (last 5 % of the run, all rows within 50 um of the floor), and the rms of dz/dt from the
        # positions of consecutive rows over the same window: they differ when the sphere oscillates
        # faster than the rows sample it
        ks = [k for k in range(1, len(z)) if t[k] >= 0.95 * t[-1]]
        if len(ks) > 5 and all(abs(z[k] - R) < 0.00005 for k in ks):
            res["rest_speed_rms"] = math.sqrt(sum(speed[k] ** 2 for k in ks) / len(ks))
            dz = [(z[k] - z[k - 1]) / (t[k] - t[k - 1]) for k in ks]
            res["rest_dzdt_rms"] = math.sqrt(sum(v * v for v in dz) / len(dz))
            res["rest_gap_range_um"] = [1e6 * (min(z[k] for k in ks) - R), 1e6 * (max(z[k] for k in ks) - R)]
        else:
            res["rest_speed_rms"] = None
        res["series"] = dict(t=t, gap=[zz - R for zz in z], speed=speed)
    return res


def resolutions_present():
    ns = set()
    if os.path.isdir(RUNS):
        for name in os.listdir(RUNS):
            m = re.match(r"E\d_N([0-9p]+)$", name)
            if m:
                ns.add(float(m.group(1).replace("p", ".")))
    return sorted(ns)


def charts(results, extra=()):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    paths = []
    ok = [r for r in results if "peak_speed" in r]
    ns = sorted({r["N"] for r in ok})
    styles = ["-", "--", "-.", ":"]
    # velocity vs time, one chart per case, all resolutions
    for case in CASES:
        rs = sorted([r for r in ok if r["case"] == case], key=lambda r: r["N"])
        if not rs:
            continue
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
        for k, r in enumerate(rs):
            s = r["series"]
            a1.plot(s["t"], s["speed"], styles[k % 4], label="N = %g (dx %.3g mm)" % (r["N"], r["dx"] * 1e3))
            a2.plot(s["t"], [g * 1e3 for g in s["gap"]], styles[k % 4], label="N = %g" % r["N"])
        for e in [e for e in extra if e["case"] == case and "series" in e]:
            s = e["series"]
            a1.plot(s["t"], s["speed"], color="0.4", lw=1.0, label="N = %g, Mach %g (tau %.2f)" % (e["N"], e["mach"], e["tau"]))
            a2.plot(s["t"], [g * 1e3 for g in s["gap"]], color="0.4", lw=1.0, label="N = %g, Mach %g" % (e["N"], e["mach"]))
        a1.axhline(CASES[case]["u_inf"], color="k", lw=0.8, ls=":", label="u_inf (unbounded) %.3f m/s" % CASES[case]["u_inf"])
        a1.set_xlabel("time [s]"); a1.set_ylabel("settling speed -v_z [m/s]")
        a1.set_title("%s (Re %.1f): settling speed" % (case, CASES[case]["Re"]))
        a1.legend(fontsize=8); a1.grid(alpha=0.3)
        a2.set_xlabel("time [s]"); a2.set_ylabel("gap to the floor [mm]")
        a2.set_title("%s: trajectory (bottom of sphere)" % case)
        a2.legend(fontsize=8); a2.grid(alpha=0.3)
        fig.tight_layout()
        p = os.path.join(HERE, "velocity_%s.png" % case)
        fig.savefig(p, dpi=110); plt.close(fig)
        paths.append(p)
    # speed against accuracy
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    ax2 = ax.twinx()
    for case in CASES:
        rs = sorted([r for r in ok if r["case"] == case], key=lambda r: r["N"])
        if not rs:
            continue
        x = [r["N"] for r in rs]
        ax.plot(x, [abs(r["peak_error_pct"]) for r in rs], "o-", color=COLORS[case], label="%s |error| %%" % case)
        ax2.plot(x, [r["wall_s_per_sim_s"] for r in rs], "s--", color=COLORS[case], alpha=0.6, label="%s wall s / sim s" % case)
    ax.axhline(3.0, color="k", lw=0.8, ls=":")
    ax.text(ns[0] if ns else 3, 3.2, "target 3 %", fontsize=8)
    ax.set_xlabel("cells per diameter N")
    ax.set_ylabel("|peak speed - u_inf| / u_inf  [%]  (solid)")
    ax2.set_ylabel("wall seconds per simulated second (dashed)")
    ax2.set_yscale("log")
    ax.set_title("Speed against accuracy (lavapipe CPU, 2 cores)")
    h1, l1 = ax.get_legend_handles_labels(); h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=7, loc="upper right", ncol=2)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    p = os.path.join(HERE, "speed_vs_accuracy.png")
    fig.savefig(p, dpi=110); plt.close(fig)
    paths.append(p)
    return paths


def fmt(v, f):
    return "-" if v is None else f % v


def make_findings(ok, extra=()):
    out = []
    by = {}
    for r in ok:
        by.setdefault(r["case"], []).append(r)
    for c in by:
        by[c].sort(key=lambda r: r["N"])
    line = []
    for c in sorted(by):
        line.append("%s (tau %s): %s" % (c, " / ".join("%.3f" % r["tau"] for r in by[c] if r.get("tau")),
                                         ", ".join("%+.1f %% at N = %g" % (r["peak_error_pct"], r["N"]) for r in by[c])))
    out.append("- **Peak speed error against u_inf, per case and resolution:** " + "; ".join(line) + ".")
    out.append(
        "- **At a given N the error falls from the most viscous case to the least viscous:** E1 (largest tau, "
        "lowest Re) settles *faster* than the unbounded u_inf, although the box walls alone should make it "
        "slower; E4 (tau closest to 1/2, highest Re) settles slower. A sphere that falls too fast feels too "
        "little drag: its effective hydrodynamic radius is smaller than 7.5 mm. Across the cases tau and Re "
        "change together, so these runs alone cannot say which one drives it; the tau check below changes "
        "only tau. With refinement the low-Re errors shrink (E1 %s %% at N = %s) even though tau - 1/2 "
        "grows with N at fixed Mach." % (" -> ".join("%+.1f" % r["peak_error_pct"] for r in by.get("E1", [])),
                                       ", ".join("%g" % r["N"] for r in by.get("E1", []))))
    if extra:
        for e in extra:
            base = next((r for r in ok if r["case"] == e["case"] and r["N"] == e["N"]), None)
            if base and "peak_speed" in e:
                out.append(
                    "- **Tau check (%s, N = %g):** Mach %g -> %g lowers tau %.3f -> %.3f and moves the peak error "
                    "%+.1f %% -> %+.1f %% (mean speed over the 80-40 mm gap %.4f -> %.4f m/s), at %.1fx the "
                    "wall time." % (e["case"], e["N"], base["mach"], e["mach"], base["tau"], e["tau"],
                                    base["peak_error_pct"], e["peak_error_pct"], base["plateau_speed"],
                                    e["plateau_speed"], e["wall_s_per_sim_s"] / base["wall_s_per_sim_s"]) +
                    " Halving dt also halves the Mach number, but compressibility errors at Mach 0.1 are of order "
                    "Ma^2 = 1 %, so most of this shift is tau: the IMB sphere's effective radius depends on tau, "
                    "and a large part of the low-Re excess at fixed Mach 0.1 is that dependence, not resolution. "
                    "Choosing dt so that tau stays near 0.6-0.9 (here: a lower Mach for E1/E2) is the cheap fix; "
                    "it costs steps in proportion.")
    e3 = ", ".join("%+.1f %% at N = %g" % (r["peak_error_pct"], r["N"]) for r in by.get("E3", []))
    e4 = ", ".join("%+.1f %% at N = %g" % (r["peak_error_pct"], r["N"]) for r in by.get("E4", []))
    out.append(
        "- **Errors that cross zero are not accuracy.** E3 (%s) crosses zero between N = 3 and 6: a too-small "
        "effective radius (too fast) meets the wall effect (too slow); a small error there is not evidence "
        "that the sphere is resolved. E4 (%s) settles near -6 %% from N = 6 on, which is plausibly the size "
        "of the box-wall and floor effect at Re 32, i.e. possibly already converged for this box; "
        "without the experimental curve that cannot be decided here." % (e3, e4))
    out.append(
        "- **Coarse grids ripple.** At N = 3 the speed oscillates with the period of the sphere crossing a "
        "cell (visible in the velocity charts); the peak is then a ripple maximum, the mean speed over the "
        "80-40 mm gap (second table) is the steadier number.")
    out.append(
        "- **The high-Stokes case (E4) only just reaches its plateau.** Its peak comes 20-25 mm above the "
        "floor, after which the floor decelerates it; 1.3 x 120 mm / u_inf is just enough simulated time "
        "for it to reach the floor (final gaps in the second table).")
    rest = [r for r in ok if r.get("rest_speed_rms") is not None]
    loud = [r for r in rest if r["rest_speed_rms"] > 1e-3]
    quiet = [r for r in rest if r["rest_speed_rms"] <= 1e-3]
    if loud:
        out.append(
            "- **Surprise: a sphere resting on the floor can keep reporting a velocity.** Over the last 5 %% of "
            "the run, with the sphere on the floor, the reported v_z has an rms of %s, while dz/dt from "
            "consecutive rows is only %s, and the gap stays within micrometres of contact (%s). The "
            "sphere oscillates at or just above the floor faster than the rows sample it, probably a limit "
            "cycle of the coupling: the IMB force answers the velocity sent at the start of a fluid step and "
            "is then held constant over all the DEM sub-steps of that step (%s). %s It does not touch the peak "
            "speed, but it matters for beds at rest: worth its own issue (e.g. send the fluid a velocity "
            "averaged over the sub-steps, or relax the hydrodynamic force)." % (
                ", ".join("%.1f mm/s (%s N=%g)" % (1e3 * r["rest_speed_rms"], r["case"], r["N"]) for r in loud),
                ", ".join("%.2f mm/s" % (1e3 * r["rest_dzdt_rms"]) for r in loud),
                ", ".join("%.1f to %.1f um" % tuple(r["rest_gap_range_um"]) for r in loud),
                ", ".join("%s N=%g: %s" % (r["case"], r["N"], r.get("dem_substeps")) for r in loud),
                ("Quiet (rms below 1 mm/s): " + ", ".join("%s N=%g" % (r["case"], r["N"]) for r in quiet) + ".") if quiet else "")
            + "".join(" The tau-check run %s N=%g at Mach %g (half the fluid dt, %s DEM sub-steps, tau %.2f) is quiet at "
                      "rest (rms %.1e mm/s), which ties the chatter to the fluid time step / tau of the coupling, "
                      "not to the contact alone." % (e["case"], e["N"], e["mach"], e.get("dem_substeps"), e["tau"],
                                                      1e3 * e["rest_speed_rms"])
                      for e in extra if e.get("rest_speed_rms") is not None and e["rest_speed_rms"] < 1e-3))
    bad = [r for r in ok if r.get("exit_code") != 0]
    out.append("- **Stability:** " + ("every run completed (exit 0, no health-check failure); tau stayed above "
               "%.3f (E4 at N = 3), far from the 0.5005 limit." % min(r["tau"] for r in ok if r.get("tau"))
               if not bad else "runs that did not complete: " + ", ".join("%s N=%g (%s)" % (r["case"], r["N"], r["exit_reason"]) for r in bad)))
    return "\n".join(out)


def report(results, chart_paths, extra=()):
    ok = [r for r in results if "peak_speed" in r]
    rows = []
    for r in sorted(results, key=lambda r: (r["case"], r["N"])):
        rows.append("| %s | %g | %s | %.3f | %s | %s | %s | %s | %s | %s | %s |" % (
            r["case"], r["N"], "%dx%dx%d" % tuple(r["cells"]), r["u_inf"],
            fmt(r.get("peak_speed"), "%.4f"), fmt(r.get("peak_error_pct"), "%+.1f"),
            fmt(r.get("tau"), "%.4f"), fmt(r.get("wall_s_per_sim_s"), "%.0f"),
            fmt(r.get("wall_time_s"), "%.0f"), fmt(r.get("mlups"), "%.2f"),
            "lavapipe CPU" + ("" if r.get("exit_code") == 0 else " (exit %s: %s)" % (r.get("exit_code"), r.get("exit_reason")))))
    table = "\n".join(rows)
    traj = []
    for r in sorted(ok, key=lambda r: (r["case"], r["N"])):
        traj.append("| %s | %g | %.3f | %.1f | %s | %s | %s | %.2f | %.3f | %s |" % (
            r["case"], r["N"], r["peak_time"], r["peak_gap"] * 1e3, fmt(r.get("t_gap_1d"), "%.2f"),
            fmt(r.get("t_gap_0p1d"), "%.2f"), fmt(r.get("plateau_speed"), "%.4f"), r["Re_peak"],
            r["final_gap"] * 1e3, fmt(r.get("rest_speed_rms"), "%.4f")))
    traj = "\n".join(traj)
    charts_md = "\n".join("- [%s](%s)" % (os.path.basename(p), os.path.basename(p)) for p in chart_paths)
    best = {}
    for r in ok:
        if r["case"] not in best or r["N"] > best[r["case"]]["N"]:
            best[r["case"]] = r
    best_txt = "; ".join("%s %+.1f %% at N = %g" % (c, best[c]["peak_error_pct"], best[c]["N"]) for c in sorted(best))
    # cost estimate for finer grids from the measured MLUPS (cost ~ N^4: N^3 cells x N steps)
    est = []
    nmax = max([r["N"] for r in ok], default=None)
    mlups = None
    ml = [r["mlups"] for r in ok if r.get("mlups") and r["N"] == nmax]   # the largest grids run: least overhead
    if ml:
        ml.sort()
        mlups = 0.5 * (ml[(len(ml) - 1) // 2] + ml[len(ml) // 2])   # median
        for n in (12, 15, 16):
            cells = (0.1 / (D / n)) ** 2 * (0.16 / (D / n))
            steps = TIME_FACTOR * GAP0 / (MACH / math.sqrt(3) * (D / n))   # same for every case
            secs = cells * steps / (mlups * 1e6)
            est.append("| %g | %.3g mm | %.2f M | %d | %.1f h | %.1f h |" % (
                n, D / n * 1e3, cells / 1e6, steps, secs / 3600, 4 * secs / 3600))
    est = "\n".join(est)
    findings = make_findings(ok, extra)
    nmax = max([r["N"] for r in ok], default=None)
    within = ", ".join("%s" % c for c in sorted(best) if abs(best[c]["peak_error_pct"]) <= 3.0)
    within = (within + (" are" if "," in within else " is")) if within else ""
    tc_line = "?"
    for e in extra:
        base = next((r for r in ok if r["case"] == e["case"] and r["N"] == e["N"]), None)
        if base and "peak_speed" in e and e["case"] == "E1":
            tc_line = "%+.1f %% at tau %.2f to %+.1f %% at tau %.2f" % (base["peak_error_pct"], base["tau"],
                                                                        e["peak_error_pct"], e["tau"])
    tc = []
    for e in extra:
        base = next((r for r in ok if r["case"] == e["case"] and r["N"] == e["N"]), None)
        for r in ([base] if base else []) + [e]:
            if "peak_speed" in r:
                tc.append("| %s | %g | %g | %.4f | %d | %.4f | %+.1f | %s | %.0f |" % (
                    r["case"], r["N"], r["mach"], r["tau"], r["steps"], r["peak_speed"], r["peak_error_pct"],
                    fmt(r.get("plateau_speed"), "%.4f"), r["wall_s_per_sim_s"]))
    tau_check = ("Same case, same grid, only dt (hence tau) changed: if the error moves with tau the IMB "
                 "boundary's effective radius depends on the viscosity in lattice units.\n\n"
                 "| case | N | Mach | tau | steps | peak speed [m/s] | error vs u_inf [%] | mean speed, gap 80-40 mm [m/s] | wall s / sim s |\n"
                 "|---|---|---|---|---|---|---|---|---|\n" + "\n".join(tc)) if tc else "(not run)"
    text = f"""# Ten Cate et al. (2002) settling sphere with the immersed moving boundary (issue 5)

Generated by `python3 validation/imb/ten_cate.py` from the runs under `runs/`. **Device: a CPU.** No GPU
was available in this session, so every run used Mesa **lavapipe** (llvmpipe, the CPU Vulkan driver) on a
2-core machine shared with other work; the timings below are CPU timings and say nothing about GPU speed.

**Target of issue 5:** terminal velocity within 3 % at 16 cells per diameter or less.
**Reached here** (finest grid per case; error of the *peak* settling speed in the box against the
*unbounded* u_inf): {best_txt or "no completed run"}. Taken at face value {within or "no case"} within 3 %
at N = {fmt(nmax, "%g")} cells per diameter or less, far below the 16 the target allows. It is not yet the
target met: the box makes the true in-box peak lower than u_inf (see "What the error means"), the cases
cross zero error at different N, and at Mach 0.1 the error depends on tau (the tau check: E1 at N = 6
goes from {tc_line}). Issue 5's target should be judged against the experimental in-box curves, or
against u_inf in a larger box, at N = 12-15; the cost of those grids on this CPU is estimated below
(hours; minutes on a GPU).

## Set-up

- Sphere d = 15 mm, rho_p = 1120 kg/m^3, closed box 100 x 100 x 160 mm (all six faces walls, half-way
  bounce-back on the lattice, walls in the DEM), released from rest with its **bottom** 120 mm above the
  floor (centre z = 127.5 mm). Fluid rho_f and mu and u_inf per case from
  `/work/shared/reference/ten-cate-2002.md`.
- Scenes derived from `validation/scenes/ten-cate-e1.toml`: D3Q19 TRT (magic 3/16), `velocity_scale = u_inf`,
  `mach = 0.1`, so dt = 0.1/sqrt(3) dx / u_inf and tau = 1/2 + 3 nu dt / dx^2 (printed by lbm-server, in
  the table). dx = 15 mm / N. Immersed moving boundary (partially saturated cells), buoyancy on the fluid
  side, gravity and contacts in `dem-client` (soft-sphere DEM, sub-cycled).
- Simulated time 1.3 x 120 mm / u_inf (the same number of steps for every case at a given N:
  1.3 x 0.12 / (0.1/sqrt(3) x dx)); the sphere reaches the floor region in all cases.
- Each run's `scene.toml`, `summary.json`, `log.txt` and a reduced `particles.csv`
  (step,time,x,y,z,vx,vy,vz,fz of the sphere every ~1/300 of the run) are kept in `runs/<case>_N<n>/`
  (`runs/<case>_N<n>_M<mach>/` for the tau check at another Mach number). The .vti snapshot of the last
  step (`fields_interval = 0`) was deleted after each run.

## How things were measured

- **Peak speed:** the largest -v_z of the sphere (DEM velocity) over the rows of particles.csv.
- **Error:** (peak - u_inf) / u_inf, u_inf being the reference's terminal velocity in an *unbounded* fluid.
- **Trajectory:** gap = z_centre - 7.5 mm (bottom of the sphere to the floor) against time.
- **Wall time per simulated second:** summary.json `wall_time_s` (whole run: lattice set-up, DEM start,
  every step, output) divided by steps x dt. MLUPS = cells x steps / wall time. The 2 cores were shared
  with other builds and tests during these runs: runs of the same size differ by up to 2x in MLUPS, so read
  the timings as +-50 %.

## Results

| case | cells per diameter | lattice | u_inf [m/s] | peak speed [m/s] | error vs u_inf [%] | tau | wall s / sim s | wall time [s] | MLUPS | device |
|---|---|---|---|---|---|---|---|---|---|---|
{table}

Trajectory figures:

| case | N | peak at t [s] | gap at peak [mm] | t(gap = 1 d) [s] | t(gap = 0.1 d) [s] | mean speed, gap 80-40 mm [m/s] | Re at peak | final gap [mm] | rms speed at rest [m/s] |
|---|---|---|---|---|---|---|---|---|---|
{traj}

Charts:

{charts_md}

`speed_vs_accuracy.png`: x = cells per diameter, left axis |peak speed error| % (solid), right axis wall
seconds per simulated second (dashed, log scale), one colour per case.

## Findings

{findings}

## Tau check: the same grid at a lower Mach number

{tau_check}

## What the error means

The error is measured against u_inf, the terminal velocity in an unbounded fluid, as the brief of issue 5
asks. In the 100 x 100 mm box (d / width = 0.15) the walls slow the sphere, so even an exact simulation of
the experiment peaks below u_inf: a few percent at the higher Reynolds numbers (E3, E4), and more at the
lowest, because wall effects grow as Re falls (for orientation only: in creeping flow a sphere on the axis
of a *cylinder* of 100 mm diameter settles at about 0.69 u_inf, Haberman-Sayre; the square box is less
confining and Re 1.5 is not creeping flow, so E1's wall effect lies somewhere between a few percent and
that). The approach to the floor decelerates the sphere further before contact. Consequences:

- a *positive* error (faster than u_inf) is a real deficit of drag, larger against the experiment than
  the number in the table says;
- a *negative* error mixes the wall effect (physics, in the experiment too) with discretisation error;
- a fair comparison needs the experimental velocity curves of Ten Cate et al. (2002) (not in the
  reference file), or a much larger / periodic box to measure u_inf itself.

## Cost of finer resolutions on this CPU

Cells grow as N^3 and steps as N (dt proportional to dx at fixed Mach), so the cost grows as N^4. From the
median MLUPS of the finest runs here (N = {fmt(nmax, "%g")}: {fmt(mlups, "%.2f")} MLUPS on lavapipe, range {fmt(ml[0] if ml else None, "%.2f")}-{fmt(ml[-1] if ml else None, "%.2f")}, whole
coupled run, 2 cores shared with other work):

| N | dx | cells | steps (every case) | one case | E1-E4 |
|---|---|---|---|---|---|
{est}

(dx must divide 100 and 160 mm: N = 12 gives 1.25 mm, N = 15 gives 1 mm; N = 16 gives 0.9375 mm, which
does not divide 100 mm, so 16 is listed for cost only.) A GPU at a few hundred to a few thousand MLUPS
would bring N = 15 to minutes per case.
"""
    with open(os.path.join(HERE, "REPORT.md"), "w") as f:
        f.write(text)


def mach_runs():
    """(case, N, mach) of the runs at a Mach number other than the default."""
    out = []
    if os.path.isdir(RUNS):
        for name in sorted(os.listdir(RUNS)):
            m = re.match(r"(E\d)_N([0-9p]+)_M([0-9p]+)$", name)
            if m:
                out.append((m.group(1), float(m.group(2).replace("p", ".")), float(m.group(3).replace("p", "."))))
    return out


def build_outputs():
    extra = [r for r in (analyse(c, n, m) for c, n, m in mach_runs()) if r is not None]
    results = []
    for n in resolutions_present():
        for case in CASES:
            r = analyse(case, n)
            if r is not None:
                results.append(r)
    paths = charts(results, extra)
    slim = [{k: v for k, v in r.items() if k != "series"} for r in results]
    with open(os.path.join(HERE, "results.json"), "w") as f:
        json.dump(dict(reference="Ten Cate et al. 2002, Phys. Fluids 14(11) 4012; /work/shared/reference/ten-cate-2002.md",
                       device=DEVICE, sphere=dict(d=D, rho_p=RHO_P, release_centre_z=Z0, release_gap=GAP0),
                       box=BOX, mach=MACH, operator="trt", time_factor=TIME_FACTOR, runs=slim,
                       tau_check=[{k: v for k, v in r.items() if k != "series"} for r in extra]), f, indent=1)
    report(results, paths, extra)
    for r in slim:
        print("%s N=%-4g peak %s m/s  err %s %%  tau %s  wall/sim %s  (%s)" % (
            r["case"], r["N"], fmt(r.get("peak_speed"), "%.4f"), fmt(r.get("peak_error_pct"), "%+.1f"),
            fmt(r.get("tau"), "%.4f"), fmt(r.get("wall_s_per_sim_s"), "%.0f"), r.get("exit_reason")))
    return results


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("run")
    a.add_argument("N", type=float, nargs="+", help="cells per diameter")
    a.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    a.add_argument("--force", action="store_true", help="rerun pairs that already have a summary.json")
    a.add_argument("--mach", type=float, default=MACH, help="Mach number of u_inf (default 0.1; others go to runs/<case>_N<n>_M<mach>)")
    sub.add_parser("report")
    args = ap.parse_args()
    if args.cmd == "run":
        if not os.path.exists(BINARY):
            raise SystemExit("%s missing: cargo build --release --bins" % BINARY)
        for n in args.N:
            for case in args.cases:
                run_one(case, n, args.force, args.mach)
    build_outputs()


if __name__ == "__main__":
    main()
