"""What the Ten Cate report takes from the runs, for validation/imb/ten_cate.py.

lbm-server's log and the sphere's series parsed (parse_log, load_series), the terminal speed as a
plateau (plateau), a run's record (analyse) distilled into validation/imb/results/ten_cate.json
(distil), the records read back (records, record) and picked for the report (the runs in larger
boxes, with other operators, at other Mach numbers; the baseline of a run in the experiment's box),
and the drag laws' terminal velocities the report compares with (drag_law_velocity).
"""
import csv
import json
import math
import os
import re

import results as compact  # validation/imb/results.py: validation/imb/results/ten_cate.json
from ten_cate_scenes import BOX, CASES, D, MACH, OPERATOR, R, RHO_P, lattice_numbers, run_dir, spec_of


SCRIPT = "ten_cate"          # its results: validation/imb/results/ten_cate.json


DEVICE = "CPU: Mesa lavapipe (llvmpipe) Vulkan, 2 shared cores; no GPU in this session"


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
        add_trajectory(res, load_series(pp), c, ln, dt)
    return res


def add_trajectory(res, d, c, ln, dt):
    """The figures of the sphere's trajectory D (particles.csv's series) into the record RES of case C on the
    lattice LN at time step DT: the peak, the gap's times, the plateau, the speed at rest and the series."""
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


def mach_runs():
    """(case, N, mach) of the runs at a Mach number other than the default."""
    out = []
    for name in sorted(records()):
        m = re.match(r"(E\d)_N([0-9p]+)_M([0-9p]+)$", name)
        if m:
            out.append((m.group(1), float(m.group(2).replace("p", ".")), float(m.group(3).replace("p", "."))))
    return out


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


def widest(wide, case, n, mach=None):
    rs = [r for r in wide if r["case"] == case and r["N"] == n and (mach is None or r["mach"] == mach) and "terminal_speed" in r
          and r.get("exit_code") == 0]
    return max(rs, key=lambda r: (r["box"][0], r["box"][2])) if rs else None


def find_run(wide, case, n, w_mm, h_mm):
    for r in wide:
        if r["case"] == case and r["N"] == n and abs(r["box"][0] * 1e3 - w_mm) < 1e-6 and abs(r["box"][2] * 1e3 - h_mm) < 1e-6 \
                and "terminal_speed" in r and r.get("exit_code") == 0:
            return r
    return None


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


def load_short(r):
    """The 1-minute load averages before and after a run, from load.txt."""
    if not r.get("load"):
        return "-"
    la = re.findall(r"load average: ([0-9.]+)", r["load"])
    return " / ".join(la) if la else "-"
