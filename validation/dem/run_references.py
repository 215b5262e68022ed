#!/usr/bin/python3
"""Run LIGGGHTS and YADE on the validation cases and write reference/*.json + reference/*.png.

    ./install.sh                                 # once (Debian bookworm packages)
    /usr/bin/python3 run_references.py           # all cases (pour: ~40 min on 2 cores)
    /usr/bin/python3 run_references.py drop oblique
    /usr/bin/python3 run_references.py pour

Use the system python (numpy 1.x, Debian matplotlib). Decks are (re)written into decks/, raw outputs go
to work/ (not committed).
"""
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

import cases

HERE = cases.HERE
REF = os.path.join(HERE, "reference")
WORK = os.path.join(HERE, "work")
os.makedirs(REF, exist_ok=True)
os.makedirs(WORK, exist_ok=True)


def dpkg_version(pkg):
    try:
        return subprocess.run(["dpkg-query", "-W", "-f=${Version}", pkg], capture_output=True, text=True).stdout
    except OSError:
        return "?"


def liggghts_version():
    out = subprocess.run(["liggghts", "-h", "-log", "none"], capture_output=True, text=True, cwd=WORK).stdout.split("\n")[0]
    return f"{out.strip()} (Debian package liggghts {dpkg_version('liggghts')})"


def yade_version():
    return f"YADE 2023.02a (Debian package yade {dpkg_version('yade')}, yade-double)"


def run_liggghts(deck, name):
    wd = os.path.join(WORK, name + "_liggghts")
    shutil.rmtree(wd, ignore_errors=True)
    shutil.copytree(deck, wd)
    t0 = time.time()
    r = subprocess.run(["liggghts", "-in", "in.liggghts", "-log", "log.liggghts"], cwd=wd,
                       capture_output=True, text=True)
    wall = time.time() - t0
    open(os.path.join(wd, "stdout.txt"), "w").write(r.stdout + r.stderr)
    if r.returncode != 0 or "ERROR" in r.stdout:
        raise RuntimeError(f"liggghts failed in {wd}:\n{r.stdout[-2000:]}")
    m = re.findall(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", r.stdout)
    loop = float(m[-1][0]) if m else float("nan")
    return wd, wall, loop


def run_yade(params, name, threads=1):
    wd = os.path.join(WORK, name + f"_yade_j{threads}")
    shutil.rmtree(wd, ignore_errors=True)
    os.makedirs(wd)
    pj = os.path.join(wd, "params.json")
    json.dump(params, open(pj, "w"))
    t0 = time.time()
    r = subprocess.run(["yade", f"-j{threads}", "-n", "-x", os.path.join(HERE, "yade_case.py"), pj, wd],
                       cwd=wd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    wall = time.time() - t0
    open(os.path.join(wd, "stdout.txt"), "w").write(r.stdout + r.stderr)
    if "YADE_DONE" not in r.stdout:
        raise RuntimeError(f"yade failed in {wd}:\n{(r.stdout + r.stderr)[-3000:]}")
    info = json.load(open(os.path.join(wd, "info.json")))
    return wd, wall, info


def read_traj(path):
    return [[float(x) for x in line.split()] for line in open(path) if line.strip() and not line.startswith("#")]


def dump(obj, name):
    with open(os.path.join(REF, name), "w") as f:
        json.dump(obj, f, indent=1)
    print("wrote", name)


# ----------------------------------------------------------------------------------------------
SWITCHES = {
    ("liggghts", "linear"): {
        "pair_style": "gran model hooke/stiffness tangential history absolute_damping on",
        "wall": "fix wall/gran model hooke/stiffness tangential history primitive type 1 zplane 0.0 absolute_damping on",
        "normal_force": "Fn = kn d + cn v_n (v_n approach speed); NO clamp: Fn may become attractive at the end of contact",
        "tangential": "total shear displacement xi (projected onto the tangent plane each step); Ft = -kt xi - ct v_t; "
                      "if kt |xi| > mu |Fn| (Fn incl. damping, absolute value) Ft is scaled to mu |Fn|",
        "limitForce": "off (default); the variant drop_linear_limitforce turns it on (clamp Fn >= 0, as YADE)",
        "material_values": "kn, kt, gamman_abs (=cn), gammat_abs (=ct) given per type pair = the contact values",
        "integrator": "velocity Verlet (nve/sphere)",
    },
    ("liggghts", "hertz"): {
        "pair_style": "gran model hertz tangential history",
        "wall": "fix wall/gran model hertz tangential history primitive type 1 zplane 0.0 (R* = r, m* = m)",
        "normal_force": "Fn = 4/3 Y* sqrt(R*) d^1.5 + gamma_n v_n, gamma_n = 2 sqrt(5/6) |beta| sqrt(2 Y* sqrt(R* d) m*), "
                        "beta = ln e / sqrt(ln^2 e + pi^2), Y* = E / (2 (1 - nu^2)); NO clamp",
        "tangential": "kt = 8 G* sqrt(R* d), G* = E / (4 (2 - nu)(1 + nu)); gamma_t = 2 sqrt(5/6) |beta| sqrt(kt m*); "
                      "total shear displacement; Coulomb limit mu |Fn| (Fn incl. damping), no damping when sliding; "
                      "while kt |xi| is below the limit the damping -gamma_t v_t is added on top, so |Ft| can exceed mu |Fn| "
                      "at the start of a contact (tangential_damping on, the default)",
        "lever_arm": "r - d/2",
        "integrator": "velocity Verlet (nve/sphere)",
    },
    ("yade", "linear"): {
        "material": "ViscElMat(kn=2 kn, cn=2 cn, ks=2 kt, cs=2 ct, frictionAngle=atan(mu)): two identical materials combine "
                    "in series, giving the contact values kn, cn, kt, ct",
        "functors": "Ig2_Sphere_Sphere_ScGeom, Ig2_Wall_Sphere_ScGeom, Ip2_ViscElMat_ViscElMat_ViscElPhys, Law2_ScGeom_ViscElPhys_Basic",
        "wall": "utils.wall(0, axis=2, sense=1) (massless, fixed)",
        "normal_force": "Fn = kn d + cn v_n, CLAMPED to Fn >= 0",
        "tangential": "incremental shear force (rotated each step), Coulomb limit tan(phi) x clamped Fn",
        "lever_arm": "r - d/2 (force applied at the contact point)",
        "integrator": "leapfrog (NewtonIntegrator damping = 0)",
    },
    ("yade", "hertz"): {
        "material": "FrictMat(young=E, poisson=nu, frictionAngle=atan(mu))",
        "functors": "Ig2_Sphere_Sphere_ScGeom, Ig2_Wall_Sphere_ScGeom, Ip2_FrictMat_FrictMat_MindlinPhys(en=e, es=e), "
                    "Law2_ScGeom_MindlinPhys_Mindlin",
        "wall": "utils.wall(...) (massless, fixed); Mindlin uses R = r/2 for a sphere-wall contact (LIGGGHTS: r)",
        "normal_force": "Fn = 4/3 E* sqrt(R) d^1.5 + cn v_n, cn = 2 beta_n sqrt(mbar kn_tangent), kn_tangent = 2 E* sqrt(R d), "
                        "beta_n from en by Thornton et al. 2013 eq. B6 (calibrated for the clamped force), "
                        "mbar = m for a fixed wall; CLAMPED to Fn >= 0",
        "tangential": "ks = 4 Gbar sqrt(R d) / (2 - nubar) (tangent stiffness, incremental shear force rotated each step); "
                      "shear damping cs = 2 beta_s sqrt(mbar ks) from es = e; Coulomb limit tan(phi) x clamped Fn on the elastic "
                      "part; when the elastic part is below the limit the damping is added on top (total may exceed the limit)",
        "lever_arm": "force applied at the contact point (midway in the overlap): r - d/2 for equal spheres",
        "integrator": "leapfrog (NewtonIntegrator damping = 0)",
    },
}

COMMON_DEFS = {
    "overlap_m": "d = r - z (sphere-wall, wall at z = 0) or r1 + r2 - |c2 - c1| (sphere-sphere), from positions written every step",
    "contact_duration_s": "t_end - t_start, the first two zero crossings of the overlap d(t), each located by linear "
                          "interpolation between the two steps that bracket the sign change (sub-step)",
    "contact_duration_steps_s": "(number of recorded steps with d > 0) x dt: the code's own discrete contact time",
    "peak_overlap_m": "max of d over the recorded steps (dt = 1e-7 s, so sub-step refinement changes it by < 1e-12 m)",
    "restitution": "-(v_n after contact) / (v_n before contact), v_n the velocity component along the wall normal "
                   "(drop) or along the line of centres at first touch (+x, oblique, relative velocity v2 - v1); "
                   "velocities taken at the end of the run (no gravity, so constant after separation)",
    "time_origin": "t = 0 at the initial state given in params; first touch at t = 2e-5 s",
    "yade_time_stamps": "YADE (leapfrog) positions are stamped t = O.time + dt when recorded after NewtonIntegrator; its "
                        "velocities are half-step values (t - dt/2); LIGGGHTS positions and velocities are both at t",
}


def drop_case(models=("linear", "hertz")):
    out = {}
    for model in models:
        res = {}
        variants = {"liggghts": [""], "yade": [""]}
        if model == "linear":
            variants["liggghts"].append("_limitforce")
        else:
            variants["yade"].append("_bigsphere")
        P = cases.yade_params("drop", model)
        for code in ("liggghts", "yade"):
            meas = {var: drop_run(code, model, var, P) for var in variants[code]}
            doc = drop_doc(code, model, meas)
            dump(doc, f"drop_{model}_{code}.json")
            res[code] = (doc, meas)
        out[model] = res
    plot_drop(out)
    return out


def drop_run(code, model, var, P):
    """One drop run by CODE (LIGGGHTS or YADE) with the contact MODEL in the variant VAR: what it measured."""
    r = cases.DROP["radius_m"]
    dt = cases.DROP["dt_s"]
    name = f"drop_{model}{var}"
    if code == "liggghts":
        deck = cases.write_liggghts_drop(model, var)
        wd, wall, loop = run_liggghts(deck, name)
        rows = cases.read_liggghts_dump(os.path.join(wd, "traj.dump"), dt)
    else:
        pv = dict(P, variant=var)
        if var == "":
            d = os.path.join(cases.DECKS, name)
            os.makedirs(d, exist_ok=True)
            json.dump(pv, open(os.path.join(d, "params.json"), "w"), indent=1)
        wd, wall, info = run_yade(pv, name, 1)
        rows = read_traj(os.path.join(wd, "traj.txt"))
    t = [row[0] for row in rows]
    d = [r - row[3] for row in rows]
    ts, te, i0, i1 = cases.crossings(t, d)
    vz0 = cases.DROP["initial_velocity_m_s"][2]
    m = {
        "restitution": -rows[-1][6] / vz0,
        "contact_duration_s": te - ts,
        "contact_duration_steps_s": sum(1 for x in d if x > 0) * dt,
        "contact_start_s": ts, "contact_end_s": te,
        "peak_overlap_m": max(d),
        "final_velocity_m_s": rows[-1][4:7],
        "wall_time_s": wall,
        "trace": {"t_s": t[::20], "overlap_m": d[::20], "vz_m_s": [row[6] for row in rows][::20]},
    }
    return m


def drop_doc(code, model, meas):
    """The reference document of the drop by CODE with MODEL from its runs MEAS (by variant)."""
    r = cases.DROP["radius_m"]
    base = meas[""]
    doc = {
        "code": code,
        "code_version": liggghts_version() if code == "liggghts" else yade_version(),
        "case": "drop", "model": model,
        "params": {
            **{k: v for k, v in cases.DROP.items()},
            "material": dict(cases.MAT, friction=0.0),
            "linear": cases.LINEAR if model == "linear" else None,
            "model_switches": SWITCHES[(code, model)],
            "deck": f"decks/drop_{model}/" + ("in.liggghts" if code == "liggghts" else "params.json + yade_case.py"),
        },
        "analytic": (cases.linear_analytic(cases.M0) if model == "linear"
                     else cases.hertz_derived(r, None, cases.M0, None, 1.0)),
        "restitution": base["restitution"],
        "contact_duration_s": base["contact_duration_s"],
        "contact_duration_steps_s": base["contact_duration_steps_s"],
        "contact_start_s": base["contact_start_s"], "contact_end_s": base["contact_end_s"],
        "peak_overlap_m": base["peak_overlap_m"],
        "final_velocity_m_s": base["final_velocity_m_s"],
        "wall_time_s": base["wall_time_s"],
        "definitions": COMMON_DEFS,
        "trace_every_20_steps": base["trace"],
    }
    for var, m in meas.items():
        if var:
            doc.setdefault("variants", {})[var.strip("_")] = {
                "description": ("LIGGGHTS with 'limitForce on' (hooke/stiffness clamps Fn >= 0, like YADE)"
                                if var == "_limitforce" else
                                "YADE with the wall replaced by a fixed sphere of radius 100 m (R* = r (1 - 2e-5), "
                                "m* = m), i.e. the LIGGGHTS wall geometry"),
                **{k: v for k, v in m.items() if k != "trace"}}
    return doc


def plot_drop(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, len(out), figsize=(6 * len(out), 4.2))
    for ax, (model, res) in zip(axs, out.items()):
        for code, (doc, meas) in res.items():
            for var, m in meas.items():
                lab = f"{code}{(' ' + var.strip('_')) if var else ''}: e={m['restitution']:.4f}, tc={m['contact_duration_s'] * 1e6:.1f} us"
                ax.plot([x * 1e6 for x in m["trace"]["t_s"]], [x * 1e6 for x in m["trace"]["overlap_m"]],
                        "--" if var else "-", label=lab)
        ax.axhline(0, color="k", lw=0.5)
        ax.set_xlabel("t [us]")
        ax.set_ylabel("overlap [um]")
        ax.set_title(f"drop ({model}): sphere r = 2 mm on a wall at 1 m/s")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(REF, "drop.png"), dpi=110)


def oblique_case(models=("hertz", "linear")):
    out = {}
    for model in models:
        for angle in cases.OBLIQUE_ANGLES:
            P = cases.yade_params("oblique", model, angle=angle)
            for code in ("liggghts", "yade"):
                rows, wall = oblique_run(code, model, angle, P)
                doc = oblique_doc(code, model, angle, P, rows, wall)
                dump(doc, f"oblique_{model}_{angle}_{code}.json")
                out[(model, angle, code)] = doc
    plot_oblique(out)
    return out


def oblique_run(code, model, angle, P):
    """One oblique impact run by CODE (LIGGGHTS or YADE) with the contact MODEL at ANGLE: its rows and wall time."""
    dt = P["dt_s"]
    name = f"oblique_{model}_{angle}"
    if code == "liggghts":
        deck = cases.write_liggghts_oblique(model, angle)
        json.dump(P, open(os.path.join(deck, "params.json"), "w"), indent=1)
        wd, wall, loop = run_liggghts(deck, name)
        rows = cases.read_liggghts_dump(os.path.join(wd, "traj.dump"), dt)
    else:
        wd, wall, info = run_yade(P, name, 1)
        rows = read_traj(os.path.join(wd, "traj.txt"))
    return rows, wall


def oblique_doc(code, model, angle, P, rows, wall):
    """The reference document of the oblique impact by CODE with MODEL at ANGLE from its run's ROWS."""
    dt = P["dt_s"]
    r1, r2 = P["radius_m"]
    t = [row[0] for row in rows]
    d = [r1 + r2 - math.dist(row[1:4], row[10:13]) for row in rows]
    ts, te, i0, i1 = cases.crossings(t, d)
    f = rows[-1]
    v1, w1, v2, w2 = f[4:7], f[7:10], f[13:16], f[16:19]
    vi = P["initial_velocity_m_s"]
    g0 = [vi[1][k] - vi[0][k] for k in range(3)]
    g1 = [v2[k] - v1[k] for k in range(3)]
    # contact-point velocity of 2 relative to 1 (normal n = +x): v2 - v1 - (r1 w1 + r2 w2) x n
    n = [1.0, 0.0, 0.0]
    def cross(a, b):
        return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    wsum = [r1 * w1[k] + r2 * w2[k] for k in range(3)]
    vc1 = [g1[k] - cross(wsum, n)[k] for k in range(3)]
    doc = {
        "code": code,
        "code_version": liggghts_version() if code == "liggghts" else yade_version(),
        "case": "oblique", "model": model, "angle": angle, "angle_deg": angle,
        "params": {**P, "material": cases.MAT,
                   "linear": cases.LINEAR if model == "linear" else None,
                   "model_switches": SWITCHES[(code, model)],
                   "deck": f"decks/oblique_{model}_{angle}/" + ("in.liggghts" if code == "liggghts" else "params.json + yade_case.py")},
        "post": {"v1": v1, "w1": w1, "v2": v2, "w2": w2},
        "post_units": "v in m/s, w in rad/s; sphere 1 starts at negative x",
        "normal_restitution": -g1[0] / g0[0],
        "tangential_contact_velocity_ratio": vc1[1] / g0[1],
        "contact_duration_s": te - ts,
        "contact_duration_steps_s": sum(1 for x in d if x > 0) * dt,
        "peak_overlap_m": max(d),
        "wall_time_s": wall,
        "definitions": dict(COMMON_DEFS, **{
            "post": "velocities / angular velocities of both spheres at t_end (after separation they are constant)",
            "normal_restitution": "-(v2 - v1)_x after / (v2 - v1)_x before (x = line of centres at first touch)",
            "tangential_contact_velocity_ratio": "y-component of the contact-point slip velocity "
                "(v2 - v1) - (r1 w1 + r2 w2) x x_hat after, divided by (v2 - v1)_y before (+1: no tangential "
                "interaction, 0: rolling without slip at separation, < 0: tangential rebound)",
        }),
        "trace_every_20_steps": {"t_s": t[::20], "overlap_m": d[::20],
                                 "wz1_rad_s": [row[9] for row in rows][::20]},
    }
    return doc


def plot_oblique(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = sorted({(m, a) for (m, a, c) in out})
    fig, axs = plt.subplots(1, len(keys), figsize=(4.5 * len(keys), 4))
    for ax, (m, a) in zip(axs, keys):
        for code, st in (("liggghts", "-"), ("yade", "--")):
            doc = out[(m, a, code)]
            tr = doc["trace_every_20_steps"]
            ax.plot([x * 1e6 for x in tr["t_s"]], tr["wz1_rad_s"], st,
                    label=f"{code}: w1z={doc['post']['w1'][2]:.2f}, en={doc['normal_restitution']:.3f}")
        ax.set_title(f"oblique {m}, {a} deg")
        ax.set_xlabel("t [us]")
        ax.set_ylabel("w1_z [rad/s]")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(REF, "oblique.png"), dpi=110)


def table():
    """Markdown table of all results (both codes side by side), for README.md."""
    def load(n):
        p = os.path.join(REF, n)
        return json.load(open(p)) if os.path.exists(p) else None
    out = ["| case | quantity | LIGGGHTS | YADE |", "|---|---|---|---|"]
    for m in ("linear", "hertz"):
        L, Y = load(f"drop_{m}_liggghts.json"), load(f"drop_{m}_yade.json")
        if not (L and Y):
            continue
        for k, lab, f, s in (("restitution", "restitution", "%.5f", 1), ("contact_duration_s", "contact duration [us]", "%.2f", 1e6),
                             ("peak_overlap_m", "peak overlap [um]", "%.3f", 1e6)):
            out.append(f"| drop {m} | {lab} | {f % (L[k] * s)} | {f % (Y[k] * s)} |")
        for d in (L, Y):
            for vn, v in d.get("variants", {}).items():
                cell = "e = %.5f, %.2f us, %.3f um" % (v["restitution"], v["contact_duration_s"] * 1e6, v["peak_overlap_m"] * 1e6)
                out.append(f"| drop {m} | variant `{vn}` | {cell if d['code'] == 'liggghts' else ''} | {cell if d['code'] == 'yade' else ''} |")
    vec = lambda v: "(" + ", ".join("%.5f" % x for x in v[:2]) + ")"
    for m in ("hertz", "linear"):
        for a in cases.OBLIQUE_ANGLES:
            L, Y = load(f"oblique_{m}_{a}_liggghts.json"), load(f"oblique_{m}_{a}_yade.json")
            if not (L and Y):
                continue
            c = f"oblique {m} {a} deg"
            out.append(f"| {c} | v1 (x, y) [m/s] (v2 = -v1) | {vec(L['post']['v1'])} | {vec(Y['post']['v1'])} |")
            out.append(f"| {c} | w1_z = w2_z [rad/s] | %.3f | %.3f |" % (L["post"]["w1"][2], Y["post"]["w1"][2]))
            out.append(f"| {c} | normal restitution | %.4f | %.4f |" % (L["normal_restitution"], Y["normal_restitution"]))
            out.append(f"| {c} | contact slip ratio after/before | %.4f | %.4f |" % (L["tangential_contact_velocity_ratio"], Y["tangential_contact_velocity_ratio"]))
            out.append(f"| {c} | contact duration [us] | %.2f | %.2f |" % (L["contact_duration_s"] * 1e6, Y["contact_duration_s"] * 1e6))
    L, Y = load("pour_liggghts.json"), load("pour_yade.json")
    if L and Y:
        pf = lambda d: "%.4f +- %.4f (runs: %s)" % (d["packing_fraction"], d["packing_fraction_std"] or 0,
                                                    ", ".join("%.4f" % x for x in d["packing_fraction_runs"]))
        out.append(f"| pour | packing fraction (mean +- std) | {pf(L)} | {pf(Y)} |")
        bh = lambda d: "%.2f (runs: %s)" % (d["bed_height_m"] * 1e3, ", ".join("%.2f" % (x * 1e3) for x in d["bed_height_m_runs"]))
        out.append(f"| pour | bed height [mm] | {bh(L)} | {bh(Y)} |")
        ke = lambda d: "%.2e" % d["kinetic_energy_J"][-1][1]
        out.append(f"| pour | KE at 0.6 s [J] ({L['kinetic_energy_J_run']} / {Y['kinetic_energy_J_run']}) | {ke(L)} | {ke(Y)} |")
        tl = L["timings"]
        out.append("| pour | particle-steps/s, 1 process | %.3g (runs: %s) | -j1: %.3g |" % (
            L["particle_steps_per_second"], ", ".join("%.3g" % v["particle_steps_per_second"] for v in tl.values()),
            Y.get("particle_steps_per_second_j1", float("nan"))))
        out.append("| pour | particle-steps/s, YADE -j2 | | %.3g |" % Y.get("particle_steps_per_second_j2", float("nan")))
        out.append("| pour | wall time per run [s] | %s | %s |" % (
            ", ".join("%.1f" % v["wall_time_s"] for v in tl.values()),
            ", ".join("%s: %.1f" % (k.replace("yade_", ""), v["wall_time_s"]) for k, v in Y["timings"].items())))
    return "\n".join(out)


if __name__ == "__main__":
    which = sys.argv[1:] or ["drop", "oblique", "pour"]
    if "table" in which:
        print(table())
    if "drop" in which:
        drop_case()
    if "oblique" in which:
        oblique_case()
    if "pour" in which:
        import pour
        pour.main(sys.argv)
