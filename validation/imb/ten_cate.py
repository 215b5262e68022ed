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
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import results as compact  # noqa: E402  (validation/imb/results/ten_cate.json and the work folder)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
TEMPLATE = os.path.join(ROOT, "validation", "scenes", "ten-cate-e1.toml")
# LBM_SERVER: another lbm-server (with its dem-client beside it), e.g. a copy that a rebuild of
# target/ during a long run cannot replace.
BINARY = os.environ.get("LBM_SERVER", os.path.join(ROOT, "target", "release", "lbm-server"))
RUNS = compact.work("ten_cate")
SCRIPT = "ten_cate"          # its results: validation/imb/results/ten_cate.json

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


OPERATORS = ("bgk", "trt", "mrt", "trts")
# "trts": TRT with the superposition solid term (coupling.solid_collision; docs/imb.md, "The
# solid collision"); the others with Noble & Torczynski's, the default.
SUPERPOSITION = '\n[coupling]\nsolid_collision = "superposition"\n'


def op_name(op):
    return "TRT, superposition" if op == "trts" else op.upper()
OPERATOR = "trt"          # the default operator: its runs keep the folders without an operator suffix


def geometry(width=None, height=None):
    """(box, release centre z, release gap) for a box of width x width x height [m] (None: the experiment's).

    A larger box keeps the sphere centred in x, y and releases it 32.5 mm below the lid, as in the
    experiment (there: centre 127.5 mm in a 160 mm box), so the fall is height - 40 mm long.
    """
    if width is None and height is None:
        return BOX, Z0, GAP0
    w = BOX[0] if width is None else width
    h = BOX[2] if height is None else height
    z0 = h - (BOX[2] - Z0)
    return (w, w, h), z0, z0 - R


def run_dir(case, n, mach=MACH, op=OPERATOR, width=None, height=None, explicit=False):
    """RUNS/<case>_N<n>[_M<mach>][_W<w>_H<h>][_<op>] (the run's name): the suffixes only where not the default
    (Mach 0.1, the experiment's 100 x 100 x 160 mm box, TRT); w and h in mm."""
    tail = "" if mach == MACH else "_M%s" % ntag(mach)
    if width is not None or height is not None:
        box, _, _ = geometry(width, height)
        tail += "_W%s_H%s" % (ntag(round(box[0] * 1e3, 6)), ntag(round(box[2] * 1e3, 6)))
    if op != OPERATOR or explicit:
        tail += "_%s" % op
    return os.path.join(RUNS, "%s_N%s%s" % (case, ntag(n), tail))


def lattice_numbers(case, n, mach=MACH, width=None, height=None, sim_time=None):
    c = CASES[case]
    box, z0, gap0 = geometry(width, height)
    dx = D / n
    for L in box:
        cells = L / dx
        if abs(cells - round(cells)) > 1e-6:
            raise SystemExit("N = %g: dx = %g m does not divide the box side %g m" % (n, dx, L))
    dt = mach / math.sqrt(3.0) * dx / c["u_inf"]
    nu = c["mu"] / c["rho_f"]
    tau = 0.5 + 3.0 * nu * dt / dx ** 2
    t_end = TIME_FACTOR * gap0 / c["u_inf"] if sim_time is None else sim_time
    steps = int(math.ceil(t_end / dt))
    cells = [int(round(L / dx)) for L in box]
    return dict(dx=dx, dt=dt, tau=tau, nu=nu, t_end=t_end, steps=steps, cells=cells, box=box, z0=z0, gap0=gap0)


def sub1(pattern, repl, text):
    new, k = re.subn(pattern, repl, text, count=1, flags=re.M)
    if k != 1:
        raise SystemExit("template %s: no match for %r" % (TEMPLATE, pattern))
    return new


def write_scene(case, n, path, mach=MACH, op=OPERATOR, width=None, height=None, sim_time=None, explicit=False,
                storage=None):
    """The scene of (case, n) written to PATH; `storage` sets lattice.storage (None: the default, fp32)."""
    c = CASES[case]
    ln = lattice_numbers(case, n, mach, width, height, sim_time)
    wide = width is not None or height is not None
    tag = ("" if mach == MACH else "-M" + ntag(mach))
    if wide:
        tag += "-W%s-H%s" % (ntag(round(ln["box"][0] * 1e3, 6)), ntag(round(ln["box"][2] * 1e3, 6)))
    if op != OPERATOR or explicit:
        tag += "-" + op
    text = open(TEMPLATE).read()
    text = sub1(r'^name = ".*"', 'name = "ten-cate-%s-N%s%s"' % (case.lower(), ntag(n), tag), text)
    if wide:
        text = sub1(r"^max = \[0\.1, 0\.1, 0\.16\].*", "max = [%r, %r, %r]        # m" % tuple(ln["box"]), text)
    text = sub1(r"^density = .*# kg/m\^3\n(?=dynamic_viscosity)", "density = %r                      # kg/m^3\n" % c["rho_f"], text)
    text = sub1(r"^dynamic_viscosity = .*", "dynamic_viscosity = %r                # Pa s" % c["mu"], text)
    text = sub1(r"^steps = .*", "steps = %d                          # %.4g s simulated" % (ln["steps"], ln["steps"] * ln["dt"]), text)
    text = sub1(r"^dx = .*", "dx = %r                           # m: %g cells per diameter" % (ln["dx"], n), text)
    text = sub1(r'^operator = .*', 'operator = "%s"' % op[:3], text)
    if storage:
        text = sub1(r'^(operator = .*)', '\\1\nstorage = "%s"' % storage, text)
    text = sub1(r"^velocity_scale = .*", "velocity_scale = %r               # m/s: u_inf of %s" % (c["u_inf"], case), text)
    text = sub1(r"^mach = .*", "mach = %r" % mach, text)
    interval = max(1, ln["steps"] // 300)
    text = sub1(r"^\[output\]\ninterval = .*",
                "[output]\ninterval = %d                         # steps between rows of particles.csv\n"
                "fields_interval = 0                  # no snapshots (a coupled run writes them only above 0)" % interval, text)
    text = sub1(r"^density = 1120\.0.*", "density = %r                     # kg/m^3" % RHO_P, text)
    if wide:
        text = sub1(r"^position = .*", "position = [%r, %r, %r]      # m: centred in x, y; bottom %g mm above the floor"
                    % (ln["box"][0] / 2, ln["box"][1] / 2, ln["z0"], round(ln["gap0"] * 1e3, 6)), text)
    else:
        text = sub1(r"^position = .*", "position = [0.05, 0.05, %r]      # m: bottom 120 mm above the floor" % Z0, text)
    text = sub1(r"^radius = .*", "radius = %r                      # m" % R, text)
    text = text[text.index("name = "):]          # drop the template's E1 header comment
    where = ""
    if wide:
        where = "; box %g x %g x %g mm" % tuple(round(L * 1e3, 6) for L in ln["box"])
    if op != OPERATOR or explicit:
        where += "; operator %s" % op_name(op)
    if storage:
        where += "; storage %s" % storage
    text = ("# Ten Cate et al. 2002, case %s (Re %.1f, u_inf %.3f m/s), %g cells per diameter%s; generated by\n"
            "# validation/imb/ten_cate.py from validation/scenes/ten-cate-e1.toml\n" % (case, c["Re"], c["u_inf"], n, where)) + text
    if op == "trts":
        text += SUPERPOSITION
    with open(path, "w") as f:
        f.write(text)
    return ln


def reduce_csv(src, dst, keep=("step", "time", "x", "y", "z", "vx", "vy", "vz", "fz"), digits=7, row_kept=None):
    """The sphere's rows (id 0) of particles.csv, columns `keep`, `digits` significant digits; with
    `row_kept`, only the rows it accepts."""
    with open(src) as f, open(dst, "w", newline="") as g:
        r = csv.DictReader(f)
        w = csv.writer(g)
        w.writerow(keep)
        for row in r:
            if row["id"] != "0" or (row_kept and not row_kept(row)):
                continue
            w.writerow([row["step"]] + ["%.*g" % (digits, float(row[k])) for k in keep[1:]])


def uptime():
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    except OSError:
        return "?"


def run_scene(out, text):
    """Writes the scene TEXT to OUT/scene.toml and runs it into OUT/work, its output in
    OUT/log.txt; (exit code, OUT/work)."""
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "scene.toml")
    with open(path, "w") as f:
        f.write(text)
    work = os.path.join(out, "work")
    with open(os.path.join(out, "log.txt"), "w") as log:
        code = subprocess.call([BINARY, "run", path, "--out", work], stderr=log, stdout=log)
    return code, work


def run_one(case, n, force=False, mach=MACH, op=OPERATOR, width=None, height=None, sim_time=None, explicit=False,
            out=None):
    """Runs (case, n) into `out` (default: its folder in the work folder RUNS, then distilled into the
    results), unless the folder has a summary.json or the results a record of it."""
    folder = out or run_dir(case, n, mach, op, width, height, explicit)
    done = os.path.exists(os.path.join(folder, "summary.json")) or (not out and os.path.basename(folder) in records())
    if done and not force:
        print("%s N=%g: already run (%s), skipped" % (case, n, folder))
        return
    run_into(folder, case, n, mach, op, width, height, sim_time, explicit)
    if not out:
        distil([folder])


def run_into(out, case, n, mach=MACH, op=OPERATOR, width=None, height=None, sim_time=None, explicit=False,
             storage=None):
    """Writes (case, n)'s scene into OUT (with lattice.storage = `storage` where given), runs it there and
    keeps its summary.json, log.txt, load.txt and the sphere's rows of particles.csv."""
    os.makedirs(out, exist_ok=True)
    scene = os.path.join(out, "scene.toml")
    ln = write_scene(case, n, scene, mach, op, width, height, sim_time, explicit, storage)
    print("%s N=%g %s: %d x %d x %d cells, dx %.4g m, dt %.4g s, tau %.4f (predicted), %d steps, %.3g s simulated"
          % (case, n, op, *ln["cells"], ln["dx"], ln["dt"], ln["tau"], ln["steps"], ln["steps"] * ln["dt"]), flush=True)
    if ln["tau"] < 0.5005:
        print("  tau %.5f < 0.5005: skipped" % ln["tau"])
        return
    tmp = os.path.join("/tmp", "ten_cate_" + os.path.basename(out))
    shutil.rmtree(tmp, ignore_errors=True)
    env = dict(os.environ, NODEVICE_SELECT="1")
    load = ["before: " + uptime()]
    t0 = time.time()
    with open(os.path.join(out, "log.txt"), "w") as log:
        p = subprocess.run([BINARY, "run", scene, "--out", tmp], stdout=log, stderr=subprocess.STDOUT, env=env, cwd=ROOT)
    wall = time.time() - t0
    load.append("after:  " + uptime())
    with open(os.path.join(out, "load.txt"), "w") as f:   # the machine's load around the run (shared cores)
        f.write("\n".join(load) + "\n")
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


def plateau(t, gap, speed, tol=0.005):
    """Terminal (plateau) speed: the mean of the speed over the contiguous rows around its maximum that
    stay within `tol` (0.5 %) of that maximum, so the speed changes by less than 0.5 % over the window.
    Returns the mean, the window's gap range and its length of fall [m], and the rows in it."""
    i = max(range(len(speed)), key=lambda k: speed[k])
    floor = (1.0 - tol) * speed[i]
    lo = i
    while lo > 0 and speed[lo - 1] >= floor:
        lo -= 1
    hi = i
    while hi + 1 < len(speed) and speed[hi + 1] >= floor:
        hi += 1
    w = speed[lo:hi + 1]
    return dict(terminal_speed=sum(w) / len(w), window_gap=[gap[lo], gap[hi]], window_fall=gap[lo] - gap[hi],
                window_t=[t[lo], t[hi]], window_rows=len(w), window_spread_pct=100.0 * (max(w) - min(w)) / (sum(w) / len(w)))


def analyse(out, case, n, mach=MACH, op=OPERATOR, width=None, height=None, explicit=False):
    """The record of the run in folder OUT: what the report needs of it (None without a summary.json)."""
    sp = os.path.join(out, "summary.json")
    if not os.path.exists(sp):
        return None
    s = json.load(open(sp))
    c = CASES[case]
    ln = lattice_numbers(case, n, mach, width, height)
    info = parse_log(os.path.join(out, "log.txt"))
    dt = info.get("dt", ln["dt"])
    lp = os.path.join(out, "load.txt")
    res = dict(case=case, N=n, mach=mach, op=op, explicit_op=explicit, box=list(ln["box"]), release_gap=ln["gap0"],
               dir=os.path.basename(out), load=open(lp).read().strip() if os.path.exists(lp) else None,
               dx=ln["dx"], cells=info.get("cells", ln["cells"]), dt=dt,
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
                   updates_per_sim_s=(ln["cells"][0] * ln["cells"][1] * ln["cells"][2] * res["steps"] / sim_t)
                   if res["steps"] and sim_t > 0 else None,
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
        pl = plateau(t, [zz - R for zz in z], speed)
        pl["terminal_error_pct"] = 100.0 * (pl["terminal_speed"] - c["u_inf"]) / c["u_inf"]
        res.update(pl)
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
        res["series"] = dict(t=t, z=z, vz=vz)    # as particles.csv has them (7 digits): the charts' series
    return res


def spec_of(name):
    """The run folder NAME as dict(case, n, mach, op, explicit, width, height) (width, height in m; None:
    the experiment's box), None if it is no run's name."""
    m = DIR_RE.match(name)
    if not m:
        return None
    num = lambda g: None if g is None else float(g.replace("p", "."))
    return dict(case=m.group(1), n=num(m.group(2)), mach=num(m.group(3)) or MACH, op=m.group(6) or OPERATOR,
                explicit=m.group(6) is not None,
                width=None if m.group(4) is None else num(m.group(4)) * 1e-3,
                height=None if m.group(5) is None else num(m.group(5)) * 1e-3)


def charted(sp):
    """Whether the charts draw the run's series: the TRT runs but the reruns in the experiment's box."""
    return sp["op"] == OPERATOR and not (sp["explicit"] and sp["width"] is None)


def distil(folders):
    """The records of the run FOLDERS (named as run_dir names them) into the results; returns their names."""
    out = {}
    for folder in folders:
        name = os.path.basename(os.path.normpath(folder))
        sp = spec_of(name)
        r = analyse(folder, sp["case"], sp["n"], sp["mach"], sp["op"], sp["width"], sp["height"], sp["explicit"]) \
            if sp else None
        if r is None:
            print("%s: no run (no summary.json or not a run's name), not distilled" % folder)
            continue
        if not charted(sp):
            r.pop("series", None)
        out[name] = r
    compact.merge(SCRIPT, out, about=ABOUT)
    RECORDS.clear()
    return sorted(out)


ABOUT = ("Ten Cate et al. (2002) settling sphere: one record per run of validation/imb/ten_cate.py (what "
         "analyse() takes from its folder: summary.json, log.txt, load.txt, particles.csv; the series t, z, vz "
         "of the sphere for the runs the charts draw). The reference: /work/shared/reference/ten-cate-2002.md.")
RECORDS = {}


def records():
    """The records of the results, by run name (read once)."""
    if not RECORDS:
        RECORDS.update(compact.runs(SCRIPT))
    return RECORDS


def record(case, n, mach=MACH, op=OPERATOR, width=None, height=None, explicit=False):
    """The run's record as analyse() made it, its series as the charts read them (gap, speed); None if
    the results have none."""
    r = records().get(os.path.basename(run_dir(case, n, mach, op, width, height, explicit)))
    if r is None:
        return None
    r = dict(r)
    if "series" in r:
        s = r["series"]
        r["series"] = dict(t=s["t"], gap=[zz - R for zz in s["z"]], speed=[-v for v in s["vz"]])
    return r


def resolutions_present():
    ns = set()
    for name in records():
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
        ax2.plot(x, [r["updates_per_sim_s"] / 1e9 for r in rs], "s--", color=COLORS[case], alpha=0.6,
                 label="%s G cell updates / sim s" % case)
    ax.axhline(3.0, color="k", lw=0.8, ls=":")
    ax.text(ns[0] if ns else 3, 3.2, "target 3 %", fontsize=8)
    ax.set_xlabel("cells per diameter N")
    ax.set_ylabel("|peak speed - u_inf| / u_inf  [%]  (solid)")
    ax.set_title("Speed against accuracy: the cost in cell updates, any device", fontsize=10)
    fig.text(0.01, 0.01, "wall s per simulated s = 1000 G / MLUPS. MLUPS: these runs 1-14 (lavapipe, 2 cores); "
             "whole Ten Cate runs on an NVIDIA H200 2,150-2,350", fontsize=7)
    ylabel = "G lattice cell updates per simulated second (dashed)"
    paths.append(finish_speed_chart(fig, ax, ax2, "upper right", "speed_vs_accuracy.png", ylabel))
    return paths


def finish_speed_chart(fig, ax, ax2, legend_at, name, ylabel="wall seconds per simulated second (dashed)"):
    """The cost axis, the joint legend and the file of a speed-against-accuracy chart; returns its path."""
    import matplotlib.pyplot as plt
    ax2.set_ylabel(ylabel)
    ax2.set_yscale("log")
    h1, l1 = ax.get_legend_handles_labels(); h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=7, loc=legend_at, ncol=2)
    ax.grid(alpha=0.3)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    p = os.path.join(HERE, name)
    fig.savefig(p, dpi=110); plt.close(fig)
    return p


def fmt(v, f):
    return "-" if v is None else f % v


def e4_split(ok, extra, wide):
    """How the larger boxes split E4's deficit in the experiment's box (a sentence; empty without them)."""
    w = widest(wide, "E4", 6)
    b = box_baseline(w, ok, extra) if w else None
    if not w or not b:
        return ("Whether that is the box-wall and floor effect at Re 32 cannot be decided without the experimental "
                "curve or a larger box.")
    return ("The larger boxes (section \"Larger boxes\") split it: at N = 6 the terminal speed in %g x %g x %g mm is %+.1f %% "
            "from u_inf, so the experiment's box accounts for a factor %.3f (%+.1f %% of the %+.1f %%) and the other %+.1f %% "
            "is the simulation against u_inf." % (w["box"][0] * 1e3, w["box"][1] * 1e3, w["box"][2] * 1e3,
                                                  w["terminal_error_pct"], b["peak_speed"] / w["terminal_speed"],
                                                  100.0 * (b["peak_speed"] - w["terminal_speed"]) / CASES["E4"]["u_inf"],
                                                  b["peak_error_pct"], w["terminal_error_pct"]))


def make_findings(ok, extra=(), wide=()):
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
        checks = []
        for e in extra:
            base = next((r for r in ok if r["case"] == e["case"] and r["N"] == e["N"]), None)
            if base and "peak_speed" in e:
                checks.append(
                    "%s at N = %g: Mach %g -> %g lowers tau %.3f -> %.3f and moves the peak error %+.1f %% -> %+.1f %% "
                    "(mean speed over the 80-40 mm gap %.4f -> %.4f m/s)" % (
                        e["case"], e["N"], base["mach"], e["mach"], base["tau"], e["tau"], base["peak_error_pct"],
                        e["peak_error_pct"], base["plateau_speed"], e["plateau_speed"]))
        if checks:
            out.append(
                "- **Tau check** (same grid, half the time step, twice the steps): " + "; ".join(checks) + ". Halving dt "
                "also halves the Mach number, but compressibility errors at Mach 0.1 are of order Ma^2 = 1 %, so most "
                "of this shift is tau: the IMB sphere's effective radius depends on tau, and part of the low-Re "
                "excess at fixed Mach 0.1 is that dependence, not resolution. Keeping tau near 0.6-1 (a lower Mach "
                "for E1/E2) helps and costs steps in proportion, but it is not the whole fix: in a larger box E1 at "
                "Mach 0.05 is still far too fast (section \"Larger boxes\").")
    e3 = ", ".join("%+.1f %% at N = %g" % (r["peak_error_pct"], r["N"]) for r in by.get("E3", []))
    e4 = ", ".join("%+.1f %% at N = %g" % (r["peak_error_pct"], r["N"]) for r in by.get("E4", []))
    out.append(
        "- **Errors that cross zero are not accuracy.** E3 (%s) crosses zero between N = 3 and 6: a too-small "
        "effective radius (too fast) meets the wall effect (too slow); a small error there is not evidence "
        "that the sphere is resolved. E4 (%s) settles near -6 %% from N = 6 on: converged in N for this box. %s"
        % (e3, e4, e4_split(ok, extra, wide)))
    out.append(
        "- **Coarse grids ripple.** At N = 3 the speed oscillates with the period of the sphere crossing a "
        "cell (visible in the velocity charts); the peak is then a ripple maximum, the mean speed over the "
        "80-40 mm gap (second table) is the steadier number.")
    out.append(
        "- **The high-Stokes case (E4) only just reaches its plateau.** Its peak comes 20-25 mm above the "
        "floor, after which the floor decelerates it; 1.3 x 120 mm / u_inf is just enough simulated time "
        "for it to reach the floor (final gaps in the second table). The larger boxes measure what the short "
        "fall costs: see \"Where E4's box effect comes from\" below.")
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
            "speed, but it matters for beds at rest. **Fixed since these runs:** the DEM now lets the held force "
            "answer the velocity change the contacts cause within the step, at the immersed boundary's own rate "
            "rho_f V / dt (`coupling.substep_drag`, default on; docs/imb.md): E1 rerun with the current code rests "
            "with an rms of 9.6e-10 m/s at N = 3 and 2.8e-8 m/s at N = 6, and its peak speed moves by +0.91 %% and "
            "+0.08 %% (the test `a_sphere_resting_on_the_floor_stays_at_rest` guards it)." % (
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


def drag_law_velocity(case, law):
    """Terminal velocity from a standard drag law, for orientation only (each law scatters by several percent
    around the data it fits): "sn" Schiller-Naumann, Cd = 24/Re (1 + 0.15 Re^0.687); "cgw" Clift, Grace and
    Weber (1978), Cd = 24/Re (1 + 0.1315 Re^(0.82 - 0.05 log10 Re)) for Re <= 20, 24/Re (1 + 0.1935 Re^0.6305)
    for 20 < Re <= 260; "abraham" Abraham (1970), Cd = 24/9.06^2 (1 + 9.06/sqrt(Re))^2."""
    c = CASES[case]
    return terminal_velocity(c["rho_f"], c["mu"], RHO_P, D, law, c["u_inf"])


def terminal_velocity(rho_f, mu, rho_p, d, law, u):
    """Terminal velocity of a sphere of diameter d and density rho_p in a fluid (rho_f, mu) by the
    drag law `law` of drag_law_velocity, iterated from the guess u."""
    for _ in range(200):
        re_ = rho_f * u * d / mu
        if law == "sn":
            cd = 24.0 / re_ * (1.0 + 0.15 * re_ ** 0.687)
        elif law == "abraham":
            cd = 24.0 / 9.06 ** 2 * (1.0 + 9.06 / math.sqrt(re_)) ** 2
        elif re_ <= 20.0:
            cd = 24.0 / re_ * (1.0 + 0.1315 * re_ ** (0.82 - 0.05 * math.log10(re_)))
        else:
            cd = 24.0 / re_ * (1.0 + 0.1935 * re_ ** 0.6305)
        u = math.sqrt(4.0 / 3.0 * (rho_p / rho_f - 1.0) * 9.81 * d / cd)
    return u


def widest(wide, case, n, mach=None):
    rs = [r for r in wide if r["case"] == case and r["N"] == n and (mach is None or r["mach"] == mach) and "terminal_speed" in r
          and r.get("exit_code") == 0]
    return max(rs, key=lambda r: (r["box"][0], r["box"][2])) if rs else None


def narrative(results, extra, wide, ops, opw=()):
    """The prose of the wide-box and operator sections, the headline and "What the error means", from the runs."""
    ok = [r for r in results if "peak_speed" in r]
    pct = lambda v: "%+.1f %%" % v
    box_txt = lambda r: "%g x %g x %g mm" % tuple(round(L * 1e3, 3) for L in r["box"])
    # ---- wide boxes
    wide_intro = (
        "The table above compares the peak speed *in the experiment's box* with u_inf, the terminal velocity in an "
        "*unbounded* fluid. To separate the box from the method, the same cases were run in larger closed boxes "
        "(all six faces walls, as before): width = depth W, height H, the sphere centred in x and y and released "
        "from rest 32.5 mm below the lid as in the experiment, so it falls H - 40 mm before touching the floor; "
        "same fluid, sphere, operator (TRT) and Mach number as the matching run in the experiment's box "
        "(BGK and MRT in a larger box: section \"Operators\"). "
        "**Terminal (plateau) speed:** the mean of -v_z over the contiguous rows of particles.csv around the "
        "maximum speed in which the speed stays within 0.5 % of that maximum (so it changes by less than 0.5 % "
        "over the window; the window's gap range and length of fall are in the table; a window of several "
        "diameters is a plateau, not a passing maximum). **Error:** (terminal - u_inf) / u_inf. **Wall effect:** "
        "(peak speed in the 100 x 100 x 160 mm box) / (terminal speed in the larger box) at the same N and Mach; "
        "1 means no effect of the box.\n\n"
        "Choice of boxes (cost on this CPU ~ cells x steps / (5-10 MLUPS), one run at a time, the cores shared "
        "with another session): N = 6 (dx 2.5 mm) for the width scans, widths 100, 200, 300 mm (d / W = 0.15, "
        "0.075, 0.05). E4 (and E3 at N = 6, 300 mm wide) in 320 mm tall boxes (280 mm of fall: E4, the highest Stokes number, needs "
        "about 100 mm of fall to come within 0.5 % of its plateau, and in the 160 mm box only just gets there). "
        "E1 (Re 1.5) at Mach 0.05 (tau 0.85; the tau check shows that tau 1.2 at Mach 0.1 biases it) in 240 mm "
        "tall boxes (200 mm of fall: E1 reaches its plateau within ~40 mm, but at low Re the lid and the floor "
        "reach further). N = 9 (dx 1.667 mm) in 200 x 200 x 240 mm, not 300 mm wide: 300 x 300 x 240 mm at "
        "N = 9 is 4.7 M cells x 2500-3000 steps, 20-40 min here; a run at N = 6 in the same 200 x 200 x 240 mm box "
        "gives the N = 6 -> 9 comparison in one box (E4, E1, E3). E3 last, as time allowed: N = 6 and 9 in "
        "200 x 200 x 240 mm, N = 6 in 300 x 300 x 320 mm. Then, in a later session: E2 at N = 6, 9 and 12 and "
        "E3 at N = 12 in 200 x 200 x 240 mm; E4 at N = 12 and 16 in 150 x 150 x 240 mm (the largest box N = 16 "
        "fits on lavapipe: 8.4 M cells); E1 at N = 12 (Mach 0.05, 200 x 200 x 240 mm, 4.9 M cells x 7206 steps): "
        "a first run was killed by the system at step 5798 for memory (a growth of about 1 byte per cell per "
        "coupled step on lavapipe), rerun to the end after the fix. Simulated time: long enough for the sphere to "
        "reach the floor region (steps in the table); the runs stop before the sphere rests on the floor.")
    bullets = []
    for case in CASES:
        rc = [r for r in wide if r["case"] == case and "terminal_speed" in r]
        if not rc:
            continue
        c = CASES[case]
        for n, mach in sorted({(r["N"], r["mach"]) for r in rc}, key=lambda k: (k[0], -k[1])):
            rn = sorted([r for r in rc if r["N"] == n and r["mach"] == mach], key=lambda r: (r["box"][2], r["box"][0]))
            base = box_baseline(rn[0], results, extra)
            parts = ["%s: %.4f m/s (%s, window %.0f mm of fall, wall effect %s)" % (
                box_txt(r), r["terminal_speed"], pct(r["terminal_error_pct"]), r["window_fall"] * 1e3,
                fmt(base["peak_speed"] / r["terminal_speed"] if base else None, "%.3f")) if r.get("exit_code") == 0 else
                "%s: stopped (%s) before its plateau, %.4f m/s over its last %.0f mm: not a terminal speed" % (
                    box_txt(r), r.get("exit_reason"), r["terminal_speed"], r["window_fall"] * 1e3) for r in rn]
            bullets.append("- **%s, N = %g, Mach %g (tau %.3f):** in the experiment's box the peak is %s m/s (%s); %s." % (
                case, n, rn[0]["mach"], rn[0]["tau"], fmt(base["peak_speed"] if base else None, "%.4f"),
                pct(base["peak_error_pct"]) if base else "-", "; ".join(parts)))
    # the width trend at the N with the most widths, per case
    trend = []
    for case in CASES:
        for n in sorted({r["N"] for r in wide if r["case"] == case}):
            tall = {}
            for r in wide:
                if r["case"] == case and r["N"] == n and "terminal_speed" in r:
                    tall.setdefault((r["box"][2], r["mach"]), []).append(r)
            for (h, _), rs in tall.items():
                if len(rs) >= 3:
                    rs.sort(key=lambda r: r["box"][0])
                    d_last = 100.0 * (rs[-1]["terminal_speed"] - rs[-2]["terminal_speed"]) / rs[-1]["terminal_speed"]
                    trend.append("%s at N = %g, H = %g mm: terminal speed %s m/s at W = %s mm; the last widening (%g -> %g mm) "
                                 "changes it by %+.2f %%" % (case, n, h * 1e3, " / ".join("%.4f" % r["terminal_speed"] for r in rs),
                                                             " / ".join("%g" % (r["box"][0] * 1e3) for r in rs),
                                                             rs[-2]["box"][0] * 1e3, rs[-1]["box"][0] * 1e3, d_last))
    if trend:
        bullets.append("- **Width convergence:** " + "; ".join(trend) + ". Lateral wall effects fall off with the "
                       "width; a last step that changes the speed by a fraction of a percent puts the widest box "
                       "within about that much of the unbounded value (assuming the remaining effect decays at least "
                       "as fast as the step; not shown by a still wider box).")
    laws = "; ".join("%s: %.4f / %.4f m/s (u_inf %.3f)" % (c, drag_law_velocity(c, "sn"), drag_law_velocity(c, "cgw"), CASES[c]["u_inf"])
                     for c in CASES)
    bullets.append("- **u_inf itself** (for orientation only): standard drag laws give terminal velocities (Schiller-Naumann / "
                   "Clift-Grace-Weber) of %s. For E3 and E4 they lie within -2 to +3 %% of the reference's u_inf; for E1 "
                   "and E2 they are 5-9 %% above it. The laws differ from each other by up to 3 %%, so they cannot "
                   "arbitrate at the 3 %% level; every error in this report is against the reference's u_inf." % laws)
    wide_findings = "\n".join(bullets)
    # ---- operators
    op_intro = (
        "E3 (Re 11.6, the seed paper's case) in the experiment's box at Mach 0.1 with the three collision operators "
        "of the lattice: BGK (one rate 1/tau), TRT (magic 3/16; the runs of the main table) and MRT (d'Humieres et "
        "al. 2002 D3Q19, shear rate 1/tau, the scene's default rates for the other moments: s_e = 1.19, "
        "s_epsilon = 1.4, s_q = 1.2, s_pi = 1.4, s_m = 1.98; `[lattice.mrt]` in scene/src/lattice.rs). Same "
        "grids, steps and measurement (peak speed) as the main table. **Timings:** wall time of the whole coupled "
        "run on 2 CPU cores shared with another session's builds and runs; the 1-minute load average before and "
        "after each run is listed (2 = both cores busy); runs of the same size can differ by 2x, so read the "
        "timing ratios between operators as +-50 %. For the timing TRT was rerun beside BGK and MRT "
        "(runs `E3_N<n>_trt`, N = 3, 6, 9; the chart's dashed TRT line); the earlier TRT runs of the main table were "
        "timed under another load (no load recorded).")
    op_bullets = []
    for op in ("bgk", "mrt"):
        rs = sorted([r for r in ops if r["op"] == op and "peak_speed" in r], key=lambda r: r["N"])
        if not rs:
            continue
        items = []
        for r in rs:
            t = next((b for b in ok if b["case"] == r["case"] and b["N"] == r["N"]), None)
            items.append("N = %g: %s (TRT %s)" % (r["N"], pct(r["peak_error_pct"]), pct(t["peak_error_pct"]) if t else "-"))
        op_bullets.append("- **%s on %s, peak speed error against u_inf in the experiment's box:** %s." % (op_name(op), rs[0]["case"], "; ".join(items)))
    # operators against each other, N by N
    cmp_ = []
    for n in sorted({r["N"] for r in ops}):
        by_op = {}
        for r in ops:
            if r["N"] == n and "peak_speed" in r and not (r["op"] == OPERATOR):
                by_op[r["op"]] = r
        t = next((b for b in ok if b["case"] == "E3" and b["N"] == n), None)
        if t:
            by_op[OPERATOR] = t
        if len(by_op) >= 2:
            cmp_.append("N = %g: %s" % (n, ", ".join("%s %.4f" % (op_name(o), by_op[o]["peak_speed"]) for o in OPERATORS if o in by_op)))
    if cmp_:
        diffs_bm, diffs_tb = [], []
        for n in sorted({r["N"] for r in ops}):
            bg = next((r for r in ops if r["N"] == n and r["op"] == "bgk" and "peak_speed" in r), None)
            mr = next((r for r in ops if r["N"] == n and r["op"] == "mrt" and "peak_speed" in r), None)
            tr = next((b for b in ok if b["case"] == "E3" and b["N"] == n), None)
            u = CASES["E3"]["u_inf"]
            if bg and mr:
                diffs_bm.append(abs(100 * (mr["peak_speed"] - bg["peak_speed"]) / u))
            if bg and tr:
                diffs_tb.append("%+.1f %% at N = %g" % (100 * (tr["peak_speed"] - bg["peak_speed"]) / u, n))
        op_bullets.append("- **Peak speeds [m/s] side by side:** " + "; ".join(cmp_) + ". BGK and MRT give the same sphere "
                          "(peaks within %.1f %% of u_inf of each other at every N); TRT (magic 3/16) gives a faster one on "
                          "coarse grids, TRT - BGK = %s of u_inf, shrinking as N grows. So at N <= 9 the IMB sphere's "
                          "effective size depends on the collision operator, TRT's being the smallest (fastest). %s" % (
                              max(diffs_bm) if diffs_bm else float("nan"), ", ".join(diffs_tb), OP_END))
    timing = []
    for n in sorted({r["N"] for r in ops}):
        row = {r["op"]: r for r in ops if r["N"] == n and "wall_time_s" in r}
        if len(row) >= 2:
            timing.append("N = %g: %s" % (n, ", ".join("%s %.0f s (load %s)" % (op_name(o), row[o]["wall_time_s"], load_short(row[o]))
                                                        for o in OPERATORS if o in row)))
    if timing:
        same = []
        for r in ops:
            t = next((b for b in ok if b["case"] == r["case"] and b["N"] == r["N"]), None)
            if r["op"] == OPERATOR and t and "peak_speed" in r:
                same.append((abs(r["peak_speed"] - t["peak_speed"]) / t["peak_speed"], r["wall_time_s"] / t["wall_time_s"]))
        rerun = ""
        if same:
            mx = max(a for a, _ in same)
            rerun = (" The TRT reruns reproduce the earlier TRT runs' peak speeds (%s); their "
                     "wall times are %.2f-%.2f of the earlier runs', which shows how much the load on this shared machine "
                     "moves the timings." % ("identical to the 7 digits kept" if mx == 0 else "largest relative difference %.1e" % mx,
                                             min(b for _, b in same), max(b for _, b in same)))
        op_bullets.append("- **Wall time of the whole run** (TRT: the reruns `E3_N<n>_trt`, same steps and grid; "
                          "1-minute load before / after): " + "; ".join(timing) + ". " + OP_TIME_END + rerun)
    est = []
    for n in sorted({r["N"] for r in ops}):
        w = find_run(wide, "E3", n, 200, 240)
        t = next((b for b in ok if b["case"] == "E3" and b["N"] == n), None)
        if not (w and t):
            continue
        f = t["peak_speed"] / w["terminal_speed"]
        parts = []
        for op in ("bgk", "mrt"):
            r = next((r for r in ops if r["N"] == n and r["op"] == op and "peak_speed" in r), None)
            if r:
                parts.append("%s %+.1f %%" % (op_name(op), 100 * (r["peak_speed"] / f - CASES["E3"]["u_inf"]) / CASES["E3"]["u_inf"]))
        if parts:
            est.append("N = %g (factor %.3f; TRT measured %+.1f %%): %s" % (n, f, w["terminal_error_pct"], ", ".join(parts)))
    if est:
        op_bullets.append("- **Against u_inf without the walls (an estimate, not runs):** if the experiment's box slows the BGK "
                          "and MRT spheres by the same factor as the TRT one (measured with TRT in 200 x 200 x 240 mm, "
                          "section \"Larger boxes\"), their errors against u_inf would be %s. On that estimate BGK and MRT "
                          "are closer to u_inf than TRT at N = 6; the runs in the next item test it." % "; ".join(est))
    meas = []
    for r in opw:
        if "terminal_speed" not in r:
            continue
        t = find_run(wide, r["case"], r["N"], r["box"][0] * 1e3, r["box"][2] * 1e3)
        b = next((o for o in ops if o["case"] == r["case"] and o["N"] == r["N"] and o["op"] == r["op"] and "peak_speed" in o), None)
        meas.append("%s %s N = %g%s: %.4f m/s (%s; %s; TRT in the same box %s) [`%s`]" % (
            r["case"], op_name(r["op"]), r["N"], "" if r["mach"] == MACH else ", Mach %g" % r["mach"],
            r["terminal_speed"], pct(r["terminal_error_pct"]),
            "in the experiment's box %s, wall effect %.3f" % (pct(b["peak_error_pct"]), b["peak_speed"] / r["terminal_speed"])
            if b else "not run in the experiment's box",
            pct(t["terminal_error_pct"]) if t else "-", os.path.basename(r["dir"])))
    if meas:
        op_bullets.append("- **BGK and MRT in a larger box, measured** (%s; terminal speed as in \"Larger boxes\"; E1 and "
                          "E4 with BGK added to see whether their errors are TRT's): %s." % (box_txt(opw[0]), "; ".join(meas)))
    op_findings = "\n".join(op_bullets)
    # ---- headline and "what the error means"
    items, effects = [], []
    for case in CASES:
        for n in sorted({r["N"] for r in wide if r["case"] == case}):
            w = widest(wide, case, n)
            if w is None:
                continue
            b = box_baseline(w, results, extra)
            items.append("%s at N = %g (Mach %g, tau %.2f) %s in %s (experiment's box: %s)" % (
                case, n, w["mach"], w["tau"], pct(w["terminal_error_pct"]), box_txt(w),
                pct(b["peak_error_pct"]) if b else "not run"))
            if b:
                effects.append("%s %.3f (N = %g, %s)" % (case, b["peak_speed"] / w["terminal_speed"], n, box_txt(w)))
    headline = HEADLINE.format(items="; ".join(items)) if items else HEADLINE_NONE
    meaning = MEANING.format(effects="; ".join(effects) if effects else "not measured")
    hc, mc, wc = conclusions(results, extra, wide, opw)
    headline = headline.replace("HEADLINE_CONCLUSION", hc)
    meaning = meaning.replace("MEANING_CONCLUSION", mc)
    wide_findings = wide_findings + ("\n" + wc if wc else "")
    return wide_intro, wide_findings, op_intro, op_findings, headline, meaning


# The Mach number of each case's larger-box runs (E1 at 0.05: at 0.1 its tau, 1.2 at N = 12, biases it);
# a larger-box run at another one is a tau check ("Tau check in a larger box").
WIDE_MACH = {"E1": 0.05}


def tau_check_in_larger_boxes(tau_wide, wide_main):
    """A finding per larger-box run at another Mach number: its terminal speed against the main
    run's in the same box at the same N."""
    out = ""
    for r in tau_wide:
        if "terminal_speed" not in r:
            continue
        m = find_run(wide_main, r["case"], r["N"], r["box"][0] * 1e3, r["box"][2] * 1e3)
        if not m or "terminal_speed" not in m:
            continue
        out += ("\n- **Tau check in a larger box:** %s at N = %g in %g x %g x %g mm: tau %.3f -> %.3f (Mach %g -> "
                "%g) moves the terminal speed from %s to %s of u_inf (%.4f -> %.4f m/s): the part of the excess that "
                "the boundary's tau dependence makes (validation/lbm/REPORT.md, \"drag against tau\"); what "
                "lowering tau leaves is the resolution's and the reference's (plateau windows of %d and %d rows: "
                "a window of a few rows is a noisy speed's maximum, not its mean)." % (
                    r["case"], r["N"], *(round(L * 1e3, 3) for L in r["box"]), m["tau"], r["tau"], m["mach"],
                    r["mach"], "%+.1f %%" % m["terminal_error_pct"], "%+.1f %%" % r["terminal_error_pct"], m["terminal_speed"],
                    r["terminal_speed"], m["window_rows"], r["window_rows"]))
    return out


def find_run(wide, case, n, w_mm, h_mm):
    for r in wide:
        if r["case"] == case and r["N"] == n and abs(r["box"][0] * 1e3 - w_mm) < 1e-6 and abs(r["box"][2] * 1e3 - h_mm) < 1e-6 \
                and "terminal_speed" in r and r.get("exit_code") == 0:
            return r
    return None


def conclusions(results, extra, wide, opw=()):
    """The conclusions of the larger-box runs: (headline, "what the error means", wide-box findings)."""
    if not wide:
        return "", "", ""
    F = lambda r: "%+.1f %%" % r["terminal_error_pct"]
    e4 = {k: find_run(wide, "E4", *k) for k in [(6, 100, 320), (6, 200, 320), (6, 300, 320), (6, 200, 240), (9, 200, 240),
                                                 (12, 200, 240), (12, 150, 240), (16, 150, 240)]}
    e1 = {k: find_run(wide, "E1", *k) for k in [(6, 100, 240), (6, 200, 240), (6, 300, 240), (9, 200, 240), (12, 200, 240)]}
    e2 = {k: find_run(wide, "E2", *k) for k in [(6, 200, 240), (9, 200, 240), (12, 200, 240)]}
    e3 = {k: find_run(wide, "E3", *k) for k in [(6, 200, 240), (9, 200, 240), (12, 200, 240), (6, 300, 320)]}
    b4 = box_baseline(e4[(6, 300, 320)], results, extra) if e4[(6, 300, 320)] else None
    b1 = box_baseline(e1[(6, 300, 240)], results, extra) if e1[(6, 300, 240)] else None
    head, mean, find = [], [], []
    if e4[(6, 300, 320)] and b4:
        w = e4[(6, 300, 320)]
        t = ("**E4's %+.1f %% in the experiment's box is half box, half simulation:** at N = 6 the box lowers the "
             "peak by a factor %.3f, and in the 300 mm wide box E4 settles %s from u_inf" % (
                 b4["peak_error_pct"], b4["peak_speed"] / w["terminal_speed"], F(w)))
        if e4[(9, 200, 240)] and e4[(6, 200, 240)]:
            t += (" (in 200 x 200 x 240 mm: %s at N = 6, %s at N = 9, so refining does not remove it)" % (
                F(e4[(6, 200, 240)]), F(e4[(9, 200, 240)])))
        head.append(t + ".")
    if e1[(6, 300, 240)] and b1:
        w = e1[(6, 300, 240)]
        t = ("**The experiment's walls hide a too-fast sphere at low Re:** E1 at N = 6 (Mach 0.05, tau 0.85) peaks "
             "%+.1f %% from u_inf in the experiment's box but settles %s from it in a 300 mm wide box (wall effect %.3f)" % (
                 b1["peak_error_pct"], F(w), b1["peak_speed"] / w["terminal_speed"]))
        if e1[(9, 200, 240)] and e1[(6, 200, 240)]:
            t += ("; in 200 x 200 x 240 mm it is %s at N = 6 and %s at N = 9 (tau %.2f)" % (
                F(e1[(6, 200, 240)]), F(e1[(9, 200, 240)]), e1[(9, 200, 240)]["tau"]))
        head.append(t + ".")
    if e3[(6, 200, 240)]:
        t = "E3 in 200 x 200 x 240 mm: %s at N = 6" % F(e3[(6, 200, 240)])
        if e3[(9, 200, 240)]:
            t += ", %s at N = 9" % F(e3[(9, 200, 240)])
        if e3[(12, 200, 240)]:
            t += ", %s at N = 12" % F(e3[(12, 200, 240)])
        if e3[(6, 300, 320)]:
            t += "; %s at N = 6 in 300 x 300 x 320 mm" % F(e3[(6, 300, 320)])
        head.append(t + ".")
    # where the box's effect comes from (E4 and E1 at N = 6)
    if e4[(6, 100, 320)] and e4[(6, 300, 320)] and b4:
        tall, w = e4[(6, 100, 320)], e4[(6, 300, 320)]
        find.append(
            "- **Where E4's box effect comes from (N = 6):** the 100 x 100 x 320 mm box (the experiment's width, more "
            "than twice the fall) gives %.4f m/s against the peak %.4f m/s in the experiment's box: %.1f %% of u_inf "
            "is the short fall (E4, the highest Stokes number, approaches its plateau slowly, within 0.5 %% only after "
            "about 100 mm of fall, and in the 160 mm box the floor acts before that), %.1f %% the lateral walls (%.4f "
            "m/s at 300 mm). The same short-fall effect shows between the 240 and 320 mm tall boxes at 200 mm width "
            "(%.4f against %.4f m/s)." % (
                tall["terminal_speed"], b4["peak_speed"], 100 * (tall["terminal_speed"] - b4["peak_speed"]) / CASES["E4"]["u_inf"],
                100 * (w["terminal_speed"] - tall["terminal_speed"]) / CASES["E4"]["u_inf"], w["terminal_speed"],
                e4[(6, 200, 240)]["terminal_speed"] if e4[(6, 200, 240)] else float("nan"),
                e4[(6, 200, 320)]["terminal_speed"] if e4[(6, 200, 320)] else float("nan")))
    if e4[(9, 200, 240)] and e4[(6, 200, 240)]:
        a6, a9 = e4[(6, 200, 240)], e4[(9, 200, 240)]
        find.append(
            "- **E4 does not improve from N = 6 to 9:** in the same 200 x 200 x 240 mm box the terminal speed is %.4f "
            "m/s (%s) at N = 6 and %.4f m/s (%s) at N = 9, as in the experiment's box (-5.7 %% to -6.0 %% for N = 6-12). "
            "Applying the N = 6 width and height effect (300 x 300 x 320 against 200 x 200 x 240 mm: %+.1f %%) to "
            "N = 9 would put N = 9 near %+.1f %% (an estimate, not a run)." % (
                a6["terminal_speed"], F(a6), a9["terminal_speed"], F(a9),
                (e4[(6, 300, 320)]["terminal_error_pct"] - a6["terminal_error_pct"]) if e4[(6, 300, 320)] else float("nan"),
                (a9["terminal_error_pct"] + e4[(6, 300, 320)]["terminal_error_pct"] - a6["terminal_error_pct"]) if e4[(6, 300, 320)] else float("nan")))
    if e4[(12, 200, 240)] and e4[(9, 200, 240)] and e4[(6, 200, 240)]:
        find.append(
            "- **E4 at N = 12** (made last, with the current code: ramp solid fraction, sub-step drag), same "
            "200 x 200 x 240 mm box: %.4f m/s (%s), after %s at N = 6 and %s at N = 9: the deficit shrinks slowly "
            "with N; the N = 6 widening to 300 x 300 x 320 mm (%+.1f %%) would put it near %+.1f %% (an estimate, "
            "not a run)." % (
                e4[(12, 200, 240)]["terminal_speed"], F(e4[(12, 200, 240)]), F(e4[(6, 200, 240)]), F(e4[(9, 200, 240)]),
                (e4[(6, 300, 320)]["terminal_error_pct"] - e4[(6, 200, 240)]["terminal_error_pct"]) if e4[(6, 300, 320)] else float("nan"),
                (e4[(12, 200, 240)]["terminal_error_pct"] + e4[(6, 300, 320)]["terminal_error_pct"]
                 - e4[(6, 200, 240)]["terminal_error_pct"]) if e4[(6, 300, 320)] else float("nan")))
    if e1[(6, 100, 240)] and e1[(6, 300, 240)] and b1:
        n100, w2, w3 = e1[(6, 100, 240)], e1[(6, 200, 240)], e1[(6, 300, 240)]
        find.append(
            "- **E1 (Re 1.5): the lateral walls are everything, and the plateau is a broad maximum.** In the 100 mm "
            "wide box the height hardly matters (%.4f m/s in 240 mm, peak %.4f m/s in 160 mm); widening to 200 and "
            "300 mm raises the speed by %+.1f %% and then %+.1f %%. In the wide boxes the lid and the floor act over "
            "many diameters at this Reynolds number, so the speed stays within 0.5 %% of its maximum over only "
            "%.0f-%.0f mm of fall (%.0f mm in the 100 mm box, whose walls screen them). The 300 mm value is therefore "
            "a lower bound of E1's unbounded terminal velocity: a wider or taller box would most likely raise it further (not run)." % (
                n100["terminal_speed"], b1["peak_speed"],
                100 * (w2["terminal_speed"] - n100["terminal_speed"]) / n100["terminal_speed"] if w2 else float("nan"),
                100 * (w3["terminal_speed"] - w2["terminal_speed"]) / w2["terminal_speed"] if w2 else float("nan"),
                w3["window_fall"] * 1e3, w2["window_fall"] * 1e3 if w2 else float("nan"), n100["window_fall"] * 1e3))
    if e1[(9, 200, 240)] and e1[(6, 200, 240)]:
        a6, a9 = e1[(6, 200, 240)], e1[(9, 200, 240)]
        t = "- **E1 with N** (Mach 0.05; tau %.2f -> %.2f), 200 x 200 x 240 mm: %.4f m/s (%s) -> %.4f m/s (%s)" % (
            a6["tau"], a9["tau"], a6["terminal_speed"], F(a6), a9["terminal_speed"], F(a9))
        a12 = e1[(12, 200, 240)]
        if a12:
            t += " -> %.4f m/s (%s) at N = 12 (tau %.2f, above the 1.0 the coupled run warns about)" % (
                a12["terminal_speed"], F(a12), a12["tau"])
        find.append(t + ".")
    if e3[(6, 200, 240)]:
        b3 = box_baseline(e3[(6, 200, 240)], results, extra)
        t = "- **E3 (Re 11.6), 200 x 200 x 240 mm:** %.4f m/s (%s) at N = 6" % (e3[(6, 200, 240)]["terminal_speed"], F(e3[(6, 200, 240)]))
        if b3:
            t += " (experiment's box: peak %+.1f %%, wall effect %.3f)" % (b3["peak_error_pct"], b3["peak_speed"] / e3[(6, 200, 240)]["terminal_speed"])
        if e3[(9, 200, 240)]:
            b9 = box_baseline(e3[(9, 200, 240)], results, extra)
            t += "; %.4f m/s (%s) at N = 9" % (e3[(9, 200, 240)]["terminal_speed"], F(e3[(9, 200, 240)]))
            if b9:
                t += " (experiment's box: %+.1f %%, wall effect %.3f)" % (b9["peak_error_pct"], b9["peak_speed"] / e3[(9, 200, 240)]["terminal_speed"])
        if e3[(12, 200, 240)]:
            t += "; %.4f m/s (%s) at N = 12" % (e3[(12, 200, 240)]["terminal_speed"], F(e3[(12, 200, 240)]))
        if e3[(6, 300, 320)]:
            t += "; %.4f m/s (%s) at N = 6 in 300 x 300 x 320 mm" % (e3[(6, 300, 320)]["terminal_speed"], F(e3[(6, 300, 320)]))
            if e3[(9, 200, 240)]:
                dd = e3[(6, 300, 320)]["terminal_error_pct"] - e3[(6, 200, 240)]["terminal_error_pct"]
                t += (". Applying the N = 6 change from 200 x 200 x 240 to 300 x 300 x 320 mm (%+.1f %%) to N = 9 would "
                      "put N = 9 near %+.1f %% (an estimate, not a run)" % (dd, e3[(9, 200, 240)]["terminal_error_pct"] + dd))
        find.append(t + ". The experiment's box takes about 3 % off E3's speed, so E3's small in-box errors at N = 6-7.5 "
                    "(main table) were a too-fast sphere meeting the walls, as suspected under Findings.")
    e2_runs = [(n, e2[(n, 200, 240)]) for n in (6, 9, 12) if e2[(n, 200, 240)]]
    if e2_runs:
        sn, cgw = drag_law_velocity("E2", "sn"), drag_law_velocity("E2", "cgw")
        find.append(
            "- **E2 (Re 4.1), 200 x 200 x 240 mm, Mach 0.1:** " + "; ".join(
                "%.4f m/s at N = %g (tau %.2f; %s of u_inf, %+.1f / %+.1f %% of Schiller-Naumann / Clift-Grace-Weber)" % (
                    r["terminal_speed"], n, r["tau"], F(r), 100 * (r["terminal_speed"] / sn - 1), 100 * (r["terminal_speed"] / cgw - 1))
                for n, r in e2_runs) + ". Like E1, E2 settles faster than its u_inf and converges towards the drag laws "
            "with N; its small in-box errors (main table) were the experiment's walls.")
    a12, a16 = e4[(12, 150, 240)], e4[(16, 150, 240)]
    if a12 and a16:
        t = ("- **E4 at N = 16** (150 x 150 x 240 mm: a 200 mm wide box at N = 16 is 213.3 cells wide, and 210 mm "
             "needs 12.8 M cells, above the 8.4 M that lavapipe's 128 MiB storage binding allows): %.4f m/s (%s) "
             "against %.4f m/s (%s) at N = 12 in the same box, %+.2f %% from N = 12 to 16" % (
                 a16["terminal_speed"], F(a16), a12["terminal_speed"], F(a12),
                 100 * (a16["terminal_speed"] / a12["terminal_speed"] - 1)))
        if e4[(12, 200, 240)]:
            wall = e4[(12, 200, 240)]["terminal_error_pct"] - a12["terminal_error_pct"]
            t += ("; the 150 mm box costs %.1f %% of u_inf against 200 mm at N = 12, so N = 16 in 200 x 200 x 240 mm "
                  "would be near %+.1f %% (an estimate)" % (wall, a16["terminal_error_pct"] + wall))
        g16 = find_run(wide, "E4", 16, 210, 240)
        if g16:
            t += ("; measured on a GPU in 210 x 210 x 240 mm: %.4f m/s (%s)" % (g16["terminal_speed"], F(g16)))
        find.append(t + ".")
    allw = list(wide) + list(opw)
    badw = [r for r in allw if r.get("exit_code") != 0]
    find.append("- **Stability:** " + ("all %d runs in larger boxes completed (exit 0, no health-check failure)." % len(allw) if not badw
                else "runs that did not complete: " + ", ".join("%s (%s)" % (r["dir"], r.get("exit_reason")) for r in badw)))
    find.append(WIDE_END)
    # verdict against the target, from the widest box run per case and N
    verdict = []
    for case in CASES:
        for n in sorted({r["N"] for r in wide if r["case"] == case}):
            w = widest(wide, case, n)
            if w:
                verdict.append((case, n, w))
    inside = ["%s N = %g (%s)" % (c, n, F(w)) for c, n, w in verdict if abs(w["terminal_error_pct"]) < 2.95]
    edge = ["%s N = %g (%s)" % (c, n, F(w)) for c, n, w in verdict if 2.95 <= abs(w["terminal_error_pct"]) <= 3.5]
    outside = ["%s N = %g (%s)" % (c, n, F(w)) for c, n, w in verdict if abs(w["terminal_error_pct"]) > 3.5]
    head.append(
        "**Against u_inf in the widest box run per case and N: within 3 %%:** %s; **at the limit (3.0-3.5 %%):** %s; "
        "**outside:** %s. %s" % (", ".join(inside) or "none", ", ".join(edge) or "none", ", ".join(outside) or "none",
                                 HEADLINE_END))
    laws = law_check(verdict)
    if laws:
        head.append(laws[0])
        find.append(laws[1])
    ops_w = []
    for r in sorted(opw, key=lambda r: (r["case"], r["N"], r["op"])):
        t = find_run(wide, r["case"], r["N"], r["box"][0] * 1e3, r["box"][2] * 1e3)
        if "terminal_speed" in r and t:
            ops_w.append("%s N = %g %s %s (TRT %s)" % (r["case"], r["N"], op_name(r["op"]), F(r), F(t)))
    if ops_w:
        head.append("**These larger-box numbers are TRT's (the operator of the main table); the operator matters:** in the same "
                    "200 x 200 x 240 mm box %s (section \"Operators\")." % "; ".join(ops_w))
    return " ".join(head), MEANING_END, "\n".join(f for f in find if f)


def law_check(verdict):
    """The widest-box terminal speeds against the drag laws' terminal velocities: (headline sentence, finding)."""
    if not verdict:
        return None
    rows = []
    for case, n, w in verdict:
        sn, cgw = drag_law_velocity(case, "sn"), drag_law_velocity(case, "cgw")
        rows.append("%s N = %g %+.1f %% / %+.1f %%" % (case, n, 100 * (w["terminal_speed"] / sn - 1), 100 * (w["terminal_speed"] / cgw - 1)))
    e1 = [(n, w) for c, n, w in verdict if c == "E1"]
    head = ""
    if e1:
        n, w = max(e1, key=lambda t: t[0])
        sn = drag_law_velocity("E1", "sn")
        head = ("**E1's excess is mostly its reference:** u_inf = %.3f m/s for E1 is %.1f %% below the Schiller-Naumann "
                "terminal velocity (%.4f m/s); against that law E1 at N = %g in %s settles %+.1f %% off, and a sphere "
                "held in a stream at Re 1 (validation/lbm/REPORT.md, 8 cells per diameter, confinement fitted out) "
                "has a drag 2.2 %% below the law." % (
                    CASES["E1"]["u_inf"], 100 * (1 - CASES["E1"]["u_inf"] / sn), sn, n,
                    "%g x %g x %g mm" % tuple(round(L * 1e3, 3) for L in w["box"]), 100 * (w["terminal_speed"] / sn - 1)))
    find = ("- **The widest-box terminal speeds against the drag laws' terminal velocities** (Schiller-Naumann / "
            "Clift-Grace-Weber; the laws scatter by several percent around their data, so this is a cross-check, "
            "not the target's reference): " + "; ".join(rows) + ".")
    abraham = ", ".join("%s %+.1f %%" % (case, 100 * (drag_law_velocity(case, "abraham") / CASES[case]["u_inf"] - 1))
                        for case in CASES)
    find += ("\n- **Where u_inf comes from:** the terminal velocity of Abraham's (1970) drag correlation, "
             "Cd = 24/9.06^2 (1 + 9.06/sqrt(Re))^2, computed here for each case's fluid and sphere, lies within 0.8 %% "
             "of the reference u_inf of all four cases (%s): u_inf is a correlation's value, not a measurement in "
             "an unbounded fluid, and at Re 1.5-4 that correlation gives 7-9 %% more drag than Schiller-Naumann "
             "and Clift-Grace-Weber (terminal velocities %.1f / %.1f %% (E1) and %.1f / %.1f %% (E2) above u_inf). "
             "So at low Re the target (3 %% of u_inf) asks the simulated sphere to match one drag law among "
             "several that differ by more than 3 %%." % (
                 abraham,
                 100 * (drag_law_velocity("E1", "sn") / CASES["E1"]["u_inf"] - 1),
                 100 * (drag_law_velocity("E1", "cgw") / CASES["E1"]["u_inf"] - 1),
                 100 * (drag_law_velocity("E2", "sn") / CASES["E2"]["u_inf"] - 1),
                 100 * (drag_law_velocity("E2", "cgw") / CASES["E2"]["u_inf"] - 1)))
    return head, find


OP_END = (
    "In the experiment's box TRT has the smallest |error| at N = 6 and 9, but that is its zero crossing "
    "(too small a sphere, too fast, meeting the walls, too slow), not a better operator: without the walls "
    "the ranking reverses (estimate and runs below).")
OP_TIME_END = (
    "BGK and TRT cost the same within the noise; MRT takes about twice as long at N = 6 and 9 (more arithmetic "
    "per cell in its collision). At these small grids a good part of the wall time is per-step overhead of the "
    "coupled run (3-9 MLUPS), so the ratios at N = 12-16 or on a GPU may differ.")
HEADLINE_END = (
    "So, once the experiment's walls are taken away (TRT, as in the main table): E3 (the seed paper's case) "
    "comes within 3 % of u_inf at N = 9 and 12 (+1.0 %, +0.6 % in 200 x 200 x 240 mm); E4 converges to about "
    "-3 % (-3.3 % at N = 12 and -3.2 % at N = 16 in 150 x 150 x 240 mm, -3.0 % at N = 12 in 200 x 200 x 240 mm; "
    "wider boxes take a few tenths of a percent off), at the edge of the target; E1 and E2 settle 7-9 % faster "
    "than their u_inf at N = 9 and come closer with N, but u_inf is the terminal velocity of Abraham's "
    "correlation, which at Re 1.5-4 gives 7-9 % more drag than Schiller-Naumann and Clift-Grace-Weber: against "
    "Clift-Grace-Weber every case is within 1.6 % at N = 9 (E1 -0.2 %, E2 +1.2 %, E3 +0.1 %, E4 -1.6 %). BGK "
    "(measured in 200 x 200 x 240 mm) makes every case 1-2.5 % of u_inf slower than TRT: E3 then comes within "
    "1 % at N = 6 and 9, E4 moves further off (-4.6 % at N = 6) and E1 stays far too fast (+11.8 %). The target "
    "of issue 5 (within 3 % of u_inf at N <= 16) is therefore met for E3, at its edge for E4 (converged in N near "
    "-3 %), and not met for E1 and E2 against their u_inf, which Schiller-Naumann and Clift-Grace-Weber do not "
    "reproduce either (5-9 % apart). The small in-box errors of E1 and E2 at N = 9-12 in the table below owe much to the "
    "experiment's walls, which slow the simulated low-Re sphere by 5-11 %.")
MEANING_END = (
    "Consequences:\n\n"
    "- the box slows the simulated sphere a lot at low Re (E1) and by a few percent at higher Re (E3, E4; for "
    "E4 about a third of it because 120 mm of fall is too short for it to reach its plateau);\n"
    "- a small error in the experiment's box can hide a large error against u_inf: E1's +1.5 % in the box "
    "at N = 6 is +14 % in a 300 mm wide box. The main table's errors are not the method's error against "
    "u_inf; the larger-box numbers are (section \"Larger boxes\");\n"
    "- in the larger boxes the simulated sphere is too fast at low Re (E1, and E3 at N = 6) and too slow "
    "at the highest Re (E4); the error changes sign with Re (and with tau, which falls with Re at fixed "
    "Mach), which points at the IMB boundary's effective size, not at the box; that size also depends on "
    "the collision operator (section \"Operators\": in a larger box BGK makes the sphere 1-2.5 % of u_inf "
    "slower than TRT in every case run, closer to u_inf for E3, further for E4; no operator fixes E1);\n"
    "- the experiment itself, for E1 (its measured speed and gap over time, digitized from the paper's "
    "figures): EXPERIMENT.md (`experiment.py`, runs with the current code in the experiment's box at "
    "tau 0.85-1.2). At tau 1.03 the plateau speed (1.7-2.5 s) is +4.7 / -2.1 / -4.4 / -5.6 % of the "
    "measured speed at N = 6 / 9 / 12 / 15 and +10.2 / +3.0 / +0.6 / -0.7 % of the measured gap's "
    "slope, converging (steps of 2.3 then 1.2 % from 9 to 15 cells); the two measured curves disagree "
    "with each other by 5 % (integrated from rest, the measured speed puts the sphere on the floor by "
    "about 3.4 s, when the measured gap still reads 0.6 d), and from N = 12 the simulated plateau lies "
    "at the gap's slope; the speed over the first 3 s is within 1.05-1.71 mm/s rms of the measured one "
    "at N = 9-15. The other cases' measured curves are not in the reference files.")
WIDE_END = ""


HEADLINE_NONE = (
    "It is not yet the target met: the box makes the true in-box peak lower than u_inf (see \"What the error "
    "means\"), the cases cross zero error at different N, and at Mach 0.1 the error depends on tau. Issue 5's "
    "target should be judged against the experimental in-box curves, or against u_inf in a larger box.")

HEADLINE = (
    "But the table compares a peak *in the experiment's box* with the *unbounded* u_inf. **In larger boxes** "
    "(section \"Larger boxes\"; terminal = plateau speed, widest box run per case and N) the error against "
    "u_inf is: {items}. HEADLINE_CONCLUSION")

MEANING = (
    "The error in the main table is measured against u_inf, the terminal velocity in an unbounded fluid, as "
    "the brief of issue 5 asks, but the sphere falls in the experiment's closed 100 x 100 x 160 mm box. The "
    "larger boxes measure what that box does to the simulated sphere: the wall effect (peak in the "
    "experiment's box) / (terminal speed in the widest box run) is {effects}. MEANING_CONCLUSION")


def run_command(r):
    """The command that makes the run of record R."""
    sp = spec_of(r["dir"])
    cmd = "python3 validation/imb/ten_cate.py run %g --cases %s" % (sp["n"], sp["case"])
    if sp["mach"] != MACH:
        cmd += " --mach %g" % sp["mach"]
    if sp["width"] is not None:
        cmd += " --width %g --height %g" % (round(r["box"][0] * 1e3, 6), round(r["box"][2] * 1e3, 6))
    if sp["op"] != OPERATOR:
        cmd += " --op %s" % sp["op"]
    elif sp["explicit"]:
        cmd += " --op-suffix"
    steps = lattice_numbers(sp["case"], sp["n"], sp["mach"], sp["width"], sp["height"])["steps"]
    if r.get("steps_requested") not in (None, steps):
        cmd += " --sim-time %g" % float("%.4g" % (r["steps_requested"] * r["dt"]))
    return cmd


def summary_rows(ok, wide):
    """Per case: the peak speed at the finest N in the experiment's box, and the terminal speed in the
    widest larger box at the finest N that completed there, against u_inf."""
    rows = []
    for case in CASES:
        c = CASES[case]
        ref = "u_inf %.3f m/s (unbounded)" % c["u_inf"]
        rs = [r for r in ok if r["case"] == case]
        if rs:
            r = max(rs, key=lambda r: r["N"])
            rows.append(("%s (Re %.1f), N = %g, the experiment's box: peak speed" % (case, c["Re"], r["N"]), ref,
                         "%.4f m/s" % r["peak_speed"], "%+.1f %%" % r["peak_error_pct"], run_command(r)))
        ns = [r["N"] for r in wide if r["case"] == case and "terminal_speed" in r and r.get("exit_code") == 0]
        w = widest(wide, case, max(ns)) if ns else None
        if w:
            rows.append(("%s, N = %g, %g x %g x %g mm: terminal speed" % (
                case, w["N"], *(round(L * 1e3, 3) for L in w["box"])), ref, "%.4f m/s" % w["terminal_speed"],
                "%+.1f %%" % w["terminal_error_pct"], run_command(w)))
    return rows


def report(results, chart_paths, extra=(), wide=(), ops=(), opw=()):
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
    # Larger-box runs at another Mach number than their case's, beside one at their case's in the same
    # box and grid (a tau check in a larger box), have their own finding; the narrative compares boxes
    # at the Mach numbers of the main runs. A run alone in its box and grid (the GPU's N = 16 and 24,
    # at the Mach number that holds tau at its N = 12 value) is a main run.
    main_mach = lambda r: r["mach"] == WIDE_MACH.get(r["case"], MACH)
    tau_wide = [r for r in wide if not main_mach(r) and any(
        main_mach(o) and (o["case"], o["N"], o["box"]) == (r["case"], r["N"], r["box"]) for o in wide)]
    wide_main = [r for r in wide if r not in tau_wide]
    findings = make_findings(ok, extra, wide_main)
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
    wide_table = wide_section(wide, results, extra)
    op_table = op_section(ops, results)
    wide_intro, wide_findings, op_intro, op_findings, headline, meaning = narrative(results, extra, wide_main, ops, opw)
    wide_findings += tau_check_in_larger_boxes(tau_wide, wide_main)
    opening = compact.summary(summary_rows(ok, wide_main), "python3 validation/imb/ten_cate.py report")
    text = f"""# Ten Cate et al. (2002) settling sphere with the immersed moving boundary (issue 5)

{opening}

Generated by `python3 validation/imb/ten_cate.py report` from `results/ten_cate.json`. **Device: a CPU**, except
the larger-box runs at N = 16 in 210 x 210 x 240 mm (E1 at Mach 0.0375 and E2 at 0.075, holding tau at its
N = 12 value; E3 and E4 at 0.1), made on an NVIDIA H200 with the code of 2026-12-03 (validation/gpu/run.sh,
2026-12-04; E1 stopped at step 3900 of 12810 by the batch's time limit): every other run used Mesa
**lavapipe** (llvmpipe, the CPU Vulkan driver) on a 2-core machine shared with other work, and its
timings are CPU timings that say nothing about GPU speed.

**Target of issue 5:** terminal velocity within 3 % at 16 cells per diameter or less.
**Reached here** (finest grid per case; error of the *peak* settling speed in the box against the
*unbounded* u_inf): {best_txt or "no completed run"}. Taken at face value {within or "no case"} within 3 %
at N = {fmt(nmax, "%g")} cells per diameter or less. {headline}

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
- Each run is named `<case>_N<n>` (`<case>_N<n>_M<mach>` for the tau check at another Mach number,
  `<case>_N<n>[_M<mach>]_W<w>_H<h>` for a box of w x w x h mm, `<case>_N<n>_<op>` for the BGK and MRT
  operators and the TRT reruns, `<case>_N<n>_W<w>_H<h>_<op>` for those in a larger box). What the report
  needs of it (the numbers of its `summary.json` and log, and the sphere's time, height and vertical
  velocity every ~1/300 of the run where a chart draws them) is its record in `results/ten_cate.json`; the
  run itself (`scene.toml`, `summary.json`, `log.txt`, a reduced `particles.csv`) stays in the ignored work
  folder `work/ten_cate/`. The runs made with the larger boxes and the other operators also record `uptime`
  just before and just after the run.
- Code: every run here except the larger-box runs of E1 at N = 12, E2 (N = 6, 9, 12), E3 at N = 12
  and E4 at N = 12 (200 and 150 mm wide) and N = 16 (made last, with the current fluid code; the E1
  and E2 N = 12 and E4 150 mm runs also with the squeeze films integrated in the DEM, which act only
  below one cell of gap) and the experiment's-box runs at N = 15 (E2, E3, E4 and, in a later
  session, E1, 2026-12-02, with everything of the current code: the squeeze films and free flight
  in the DEM; these N = 15 runs shared the 2 cores with other work, so their MLUPS are low)
  predates two changes of 2026-11-24: the
  solid fraction by a distance ramp instead of 4^3 sub-samples, which moves the Zick-Homsy and
  Schiller-Naumann errors by at most 0.9 points (docs/imb.md), and the force within a fluid step
  following the velocity in the DEM (`coupling.substep_drag`), which removes the bouncing at rest
  (Findings). Rerun with the current code: peak +0.91 % (E1, N = 3), +0.08 % (E1, N = 6), +0.24 %
  (E4, N = 6); time to 75 % of the peak unchanged. Rerunning a run (`ten_cate.py run ... --force`)
  with the current code gives both.

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

`speed_vs_accuracy.png`: x = cells per diameter, left axis |peak speed error| % (solid), right axis the
cost of a simulated second in lattice cell updates (cells x steps / simulated time; dashed, log scale),
one colour per case: a device's wall time per simulated second is 1000 x that figure (in G) / its MLUPS,
so the chart holds for any device and none of this machine's noise (these runs: 1-14 MLUPS on lavapipe;
the whole Ten Cate runs at N = 16 on an NVIDIA H200: 2,150-2,350 MLUPS, BENCHMARKS.md). E3 at N = 12,
for example: 1.0 G updates per simulated second, 0.45 s per simulated second on the H200. The table's
wall s / sim s are this machine's, shared with other work.

## Findings

{findings}

## Tau check: the same grid at a lower Mach number

{tau_check}

## Larger boxes: the terminal velocity without the experiment's walls

{wide_intro}

{wide_table}

![wide boxes](wide_boxes.png)

{wide_findings}

## Operators: BGK, TRT, MRT on E3

{op_intro}

{op_table}

![operators](speed_vs_accuracy_operators.png)

{op_findings}

## What the error means

{meaning}

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
    for name in sorted(records()):
        m = re.match(r"(E\d)_N([0-9p]+)_M([0-9p]+)$", name)
        if m:
            out.append((m.group(1), float(m.group(2).replace("p", ".")), float(m.group(3).replace("p", "."))))
    return out


DIR_RE = re.compile(r"(E\d)_N([0-9p]+)(?:_M([0-9p]+))?(?:_W([0-9p]+)_H([0-9p]+))?(?:_(bgk|mrt|trts|trt))?$")


def run_specs():
    """Every run of the results as spec_of gives it."""
    return [sp for sp in (spec_of(name) for name in sorted(records())) if sp]


def wide_results():
    """Runs in a box other than the experiment's (TRT)."""
    rs = [record(sp["case"], sp["n"], sp["mach"], sp["op"], sp["width"], sp["height"], sp["explicit"])
          for sp in run_specs() if sp["width"] is not None and sp["op"] == OPERATOR]
    return sorted([r for r in rs if r is not None], key=lambda r: (r["case"], r["N"], r["mach"], r["box"][0], r["box"][2]))


def op_wide_results():
    """Runs in a box other than the experiment's with an operator other than TRT."""
    rs = [record(sp["case"], sp["n"], sp["mach"], sp["op"], sp["width"], sp["height"], sp["explicit"])
          for sp in run_specs() if sp["width"] is not None and sp["op"] != OPERATOR]
    return sorted([r for r in rs if r is not None], key=lambda r: (r["case"], r["N"], r["op"]))


def op_results():
    """Runs with an operator other than TRT, in the experiment's box at Mach 0.1."""
    rs = [record(sp["case"], sp["n"], sp["mach"], sp["op"], explicit=sp["explicit"])
          for sp in run_specs() if sp["width"] is None and sp["explicit"] and sp["mach"] == MACH]
    return sorted([r for r in rs if r is not None], key=lambda r: (r["case"], r["op"], r["N"]))


def box_baseline(r, results, extra):
    """The run in the experiment's box with the same case, N, Mach and operator as r."""
    for b in list(results) + list(extra):
        if b["case"] == r["case"] and b["N"] == r["N"] and b["mach"] == r["mach"] and b.get("op", OPERATOR) == r.get("op", OPERATOR) \
                and b["box"] == list(BOX) and "peak_speed" in b:
            return b
    return None


def wide_charts(wide, results, extra):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    paths = []
    cases = [c for c in CASES if any(r["case"] == c and "series" in r for r in wide)]
    if not cases:
        return paths
    fig, axes = plt.subplots(1, len(cases), figsize=(5.2 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases):
        c = CASES[case]
        rs = [r for r in wide if r["case"] == case and "series" in r]
        bases = []
        for r in rs:
            b = box_baseline(r, results, extra)
            if b is not None and b not in bases:
                bases.append(b)
        for k, b in enumerate(sorted(bases, key=lambda b: b["N"])):
            s = b["series"]
            ax.plot([(GAP0 - g) * 1e3 for g in s["gap"]], [v / c["u_inf"] for v in s["speed"]], color=("0.55", "0.2")[k % 2], lw=1.0,
                    ls=(":", "--")[k % 2], label="N = %g, 100 x 100 x 160 mm (experiment)" % b["N"])
        for k, r in enumerate(rs):
            s = r["series"]
            ln = ax.plot([(r["release_gap"] - g) * 1e3 for g in s["gap"]], [v / c["u_inf"] for v in s["speed"]],
                         ["-", "--", "-.", ":"][k % 4], lw=1.3,
                         label="N = %g, %g x %g x %g mm" % (r["N"], r["box"][0] * 1e3, r["box"][1] * 1e3, r["box"][2] * 1e3))
            # the plateau window and its mean
            f0, f1 = r["release_gap"] - r["window_gap"][0], r["release_gap"] - r["window_gap"][1]
            ax.plot([f0 * 1e3, f1 * 1e3], [r["terminal_speed"] / c["u_inf"]] * 2, color=ln[0].get_color(), lw=4, alpha=0.35)
        ax.axhline(1.0, color="k", lw=0.8, ls=":")
        for y in (0.97, 1.03):
            ax.axhline(y, color="k", lw=0.5, ls="--", alpha=0.4)
        ax.set_ylim(0.7, 1.2)
        ax.set_xlabel("distance fallen [mm]")
        ax.set_ylabel("settling speed / u_inf (unbounded %.3f m/s)" % c["u_inf"])
        mach = sorted({r["mach"] for r in rs})
        ax.set_title("%s (Re %.1f), Mach %s: larger boxes" % (case, c["Re"], "/".join("%g" % m for m in mach)))
        ax.legend(fontsize=6.5, loc="lower center", ncol=2)
        ax.grid(alpha=0.3)
    fig.suptitle("Settling speed against distance fallen; thick bars: plateau window (speed within 0.5 % of its maximum) and its mean; dashed: +-3 %",
                 fontsize=8)
    fig.tight_layout()
    p = os.path.join(HERE, "wide_boxes.png")
    fig.savefig(p, dpi=110); plt.close(fig)
    paths.append(p)
    return paths


OP_COLORS = {"bgk": "tab:purple", "trt": "tab:green", "mrt": "tab:brown", "trts": "tab:olive"}


def op_chart(ops, results, case="E3"):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    ax2 = ax.twinx()
    drawn = False
    for op in OPERATORS:
        src = [r for r in results if r["case"] == case] if op == OPERATOR else [r for r in ops if r["case"] == case and r["op"] == op]
        rs = sorted([r for r in src if "peak_speed" in r], key=lambda r: r["N"])
        if not rs:
            continue
        drawn = True
        x = [r["N"] for r in rs]
        ax.plot(x, [abs(r["peak_error_pct"]) for r in rs], "o-", color=OP_COLORS[op], label="%s |error| %%" % op_name(op))
        timed = rs
        if op == OPERATOR:    # TRT reruns (<case>_N<n>_trt) timed beside the BGK and MRT runs, where present
            rr = sorted([r for r in ops if r["case"] == case and r["op"] == op and "peak_speed" in r], key=lambda r: r["N"])
            timed = rr or rs
        ax2.plot([r["N"] for r in timed], [r["wall_s_per_sim_s"] for r in timed], "s--", color=OP_COLORS[op], alpha=0.7,
                 label="%s wall s / sim s%s" % (op_name(op), " (reruns)" if timed is not rs else ""))
    if not drawn:
        plt.close(fig)
        return []
    ax.axhline(3.0, color="k", lw=0.8, ls=":")
    ax.text(3, 3.2, "target 3 %", fontsize=8)
    ax.set_xlabel("cells per diameter N")
    ax.set_ylabel("|peak speed - u_inf| / u_inf  [%%]  (solid), %s" % case)
    ax.set_title("%s (Re %.1f), experiment's box, Mach 0.1: operators (lavapipe CPU, 2 shared cores)" % (case, CASES[case]["Re"]), fontsize=9)
    return [finish_speed_chart(fig, ax, ax2, "center right", "speed_vs_accuracy_operators.png")]


def load_short(r):
    """The 1-minute load averages before and after a run, from load.txt."""
    if not r.get("load"):
        return "-"
    la = re.findall(r"load average: ([0-9.]+)", r["load"])
    return " / ".join(la) if la else "-"


def wide_section(wide, results, extra):
    if not wide:
        return "(not run)"
    rows = []
    for r in wide:
        b = box_baseline(r, results, extra)
        rows.append("| %s | %g | %g | %s | %g x %g x %g | %s | %.0f | %s | %.2f | %s | %s | %.0f-%.0f (%.0f) | %s | %s | %s | %s | %s | %s | %s |" % (
            r["case"], r["N"], r["mach"], fmt(r.get("tau"), "%.3f"),
            r["box"][0] * 1e3, r["box"][1] * 1e3, r["box"][2] * 1e3, "%dx%dx%d" % tuple(r["cells"]),
            r["release_gap"] * 1e3, r["steps"], r["simulated_time_s"],
            fmt(r.get("terminal_speed"), "%.4f"), fmt(r.get("terminal_error_pct"), "%+.1f"),
            r["window_gap"][0] * 1e3, r["window_gap"][1] * 1e3, r["window_fall"] * 1e3,
            fmt(r.get("peak_speed"), "%.4f"),
            fmt(b["peak_speed"] if b else None, "%.4f"),
            fmt(b["peak_speed"] / r["terminal_speed"] if b else None, "%.3f"),
            fmt(r.get("wall_time_s"), "%.0f"), fmt(r.get("mlups"), "%.2f"), load_short(r),
            "" if r.get("exit_code") == 0 else "exit %s: %s" % (r.get("exit_code"), r.get("exit_reason"))))
    return ("| case | N | Mach | tau | box [mm] | lattice | release gap [mm] | steps | simulated [s] | terminal speed [m/s] | "
            "error vs u_inf [%] | plateau window: gap [mm] (fall) | peak [m/s] | peak in the 100 x 100 x 160 box, same N and Mach [m/s] | "
            "wall effect = box peak / terminal | wall time [s] | MLUPS | load before / after | note |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n" + "\n".join(rows))


def op_section(ops, results):
    if not ops:
        return "(not run)"
    rows = []
    trt = [r for r in results if r["case"] in {o["case"] for o in ops}]
    for r in sorted(list(ops) + trt, key=lambda r: (r["case"], r["N"], OPERATORS.index(r.get("op", OPERATOR)), r.get("explicit_op", False))):
        if "peak_speed" not in r:
            continue
        rows.append("| %s | %s | %g | %s | %s | %.4f | %+.1f | %s | %s | %.0f | %.0f | %s | %s |" % (
            r["case"], op_name(r.get("op", OPERATOR)) + (" (rerun, `%s`)" % os.path.basename(r["dir"]) if r.get("op") == OPERATOR and r.get("explicit_op") else ""),
            r["N"], "%dx%dx%d" % tuple(r["cells"]), fmt(r.get("tau"), "%.4f"),
            r["peak_speed"], r["peak_error_pct"], fmt(r.get("plateau_speed"), "%.4f"),
            r["steps"], r["wall_time_s"], r["wall_s_per_sim_s"], fmt(r.get("mlups"), "%.2f"), load_short(r)))
    return ("| case | operator | N | lattice | tau | peak speed [m/s] | error vs u_inf [%] | mean speed, gap 80-40 mm [m/s] | steps | "
            "wall time [s] | wall s / sim s | MLUPS | load before / after (1 min) |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n" + "\n".join(rows))


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


def import_runs(src, force=False, runs=RUNS, prefix=""):
    """Each DIR/<prefix><name>/ that holds a summary.json goes to RUNS/<name>/ (the work folder) as `run_one`
    leaves its runs: scene.toml, summary.json, log.txt and the sphere's rows of particles.csv. A run already
    there is kept unless `force`. Returns the folders imported."""
    done = []
    for name in sorted(os.listdir(src)):
        d = os.path.join(src, name)
        if not name.startswith(prefix) or not os.path.exists(os.path.join(d, "summary.json")):
            print("%s: no summary.json, not imported" % name)
            continue
        out = os.path.join(runs, name[len(prefix):])
        if os.path.exists(os.path.join(out, "summary.json")) and not force:
            print("%s: already in %s, kept (--force replaces it)" % (name, out))
            continue
        os.makedirs(out, exist_ok=True)
        for f in ("scene.toml", "summary.json", "log.txt"):
            if os.path.exists(os.path.join(d, f)):
                shutil.copy(os.path.join(d, f), os.path.join(out, f))
        if os.path.exists(os.path.join(d, "particles.csv")):
            reduce_csv(os.path.join(d, "particles.csv"), os.path.join(out, "particles.csv"))
        print("%s: imported into %s" % (name, out))
        done.append(out)
    return done


def run_folders(folder):
    """The run folders in FOLDER (those with a summary.json), sorted."""
    return [os.path.join(folder, name) for name in sorted(os.listdir(folder))
            if os.path.exists(os.path.join(folder, name, "summary.json"))]


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
