#!/usr/bin/python3
"""Case 3 (pour) for both codes.

    /usr/bin/python3 pour.py all                 # every run below, then the report (~40 min on 2 cores)
    /usr/bin/python3 pour.py run liggghts 0      # one run: code, perturbation k (0, 1, 2), [threads for yade]
    /usr/bin/python3 pour.py run yade 1 2
    /usr/bin/python3 pour.py report              # reference/pour_<code>.json + reference/pour.png from work/

Runs are done one after the other (never two at once) so the timings are clean.
"""
import json
import os
import sys

import cases
import run_references as rr

PLAN = [("liggghts", 0, 1), ("liggghts", 1, 1), ("liggghts", 2, 1),
        ("yade", 0, 2), ("yade", 1, 1), ("yade", 2, 1), ("yade", 0, 1)]


def run_one(code, k, threads=1, collect_only=False):
    """collect_only: measure an existing YADE work dir (wall time then = info.json mtime - params.json mtime)."""
    P = cases.POUR
    name = f"pour_run{k}"
    if collect_only:
        wd = os.path.join(rr.WORK, name + f"_yade_j{threads}")
        info = json.load(open(os.path.join(wd, "info.json")))
        wall = os.path.getmtime(os.path.join(wd, "info.json")) - os.path.getmtime(os.path.join(wd, "params.json"))
        ke = rr.read_traj(os.path.join(wd, "traj.txt"))
        final, loop, steps = info["final"], info["loop_time_s"], info["steps"]
        tag = f"{code}_j{threads}_run{k}"
    elif code == "liggghts":
        deck = cases.write_liggghts_pour(k)
        wd, wall, loop = rr.run_liggghts(deck, name)
        ke = rr.read_traj(os.path.join(wd, "ke.txt"))
        ke = [[0.0, 0.0, 0.0, float(P["n"])]] + ke
        lines = open(os.path.join(wd, "final.dump")).read().split("\n")
        last = max(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
        n = int(lines[last - 5])
        rows = [[float(x) for x in l.split()] for l in lines[last + 1:last + 1 + n]]
        rows.sort()
        final = [[r[1], r[2], r[3], r[4]] for r in rows]
        steps = int(round(P["t_end_s"] / P["dt_s"]))
        tag = f"{code}_run{k}"
    else:
        params = cases.yade_params("pour", "hertz", run=k)
        wd, wall, info = rr.run_yade(params, name, threads)
        ke = rr.read_traj(os.path.join(wd, "traj.txt"))
        final = info["final"]
        loop = info["loop_time_s"]
        steps = info["steps"]
        tag = f"{code}_j{threads}_run{k}"
    radii = [f[0] for f in final]
    pos = [f[1:4] for f in final]
    meas = cases.bed_measures(radii, pos)
    res = dict(code=code, run=k, threads=threads, n_final=len(final), wall_time_s=wall, loop_time_s=loop,
               steps=steps, particle_steps_per_second=P["n"] * steps / loop,
               kinetic_energy=[[r[0], r[1] + r[2], r[1], r[2]] for r in ke], **meas)
    json.dump(res, open(os.path.join(rr.WORK, f"pour_result_{tag}.json"), "w"))
    print(tag, {k_: v for k_, v in res.items() if k_ != "kinetic_energy"}, flush=True)
    return res


def report():
    """reference/pour_<code>.json and reference/pour.png from the runs' results in work/."""
    import statistics
    radii0, _ = cases.pour_layout(0)
    initial = {f"run{k}": cases.pour_layout(k)[1] for k in cases.POUR_RUNS}
    docs = {}
    for code in ("liggghts", "yade"):
        runs = pour_results(code)
        if not runs:
            continue
        doc = pour_doc(code, runs, radii0, initial)
        if code == "yade":
            for th in (1, 2):
                ks = [k for k in runs if k.startswith(f"yade_j{th}_")]
                if ks:
                    doc[f"particle_steps_per_second_j{th}"] = statistics.mean(runs[k]["particle_steps_per_second"] for k in ks)
                    doc[f"wall_time_s_j{th}"] = statistics.mean(runs[k]["wall_time_s"] for k in ks)
        rr.dump(doc, f"pour_{code}.json")
        docs[code] = (doc, runs)
    plot(docs)


def pour_results(code):
    """The results of CODE's pour runs in work/, by run label."""
    runs = {}
    for fn in sorted(os.listdir(rr.WORK)):
        if fn.startswith(f"pour_result_{code}_") and fn.endswith(".json"):
            runs[fn[len("pour_result_"):-5]] = json.load(open(os.path.join(rr.WORK, fn)))
    return runs


def packing_runs(code, runs):
    """The labels of the runs the packing fraction is averaged over."""
    # packing-fraction runs: every run (YADE -j1 and -j2 runs of the same k are different trajectories too)
    if code == "liggghts":
        pf_keys = [f"liggghts_run{k}" for k in cases.POUR_RUNS if f"liggghts_run{k}" in runs]
    else:
        pf_keys = [f"yade_j{th}_run{k}" for (c, k, th) in PLAN if c == "yade" and f"yade_j{th}_run{k}" in runs]
    return pf_keys


def pour_doc(code, runs, radii0, initial):
    """The reference document of CODE from its RUNS (the initial radii and positions beside them)."""
    import statistics
    P = cases.POUR
    prim = "liggghts_run0" if code == "liggghts" else "yade_j1_run0"
    if prim not in runs:
        prim = sorted(runs)[0]
    pf_keys = packing_runs(code, runs)
    pfs = [runs[k]["packing_fraction"] for k in pf_keys]
    hs = [runs[k]["bed_height_m"] for k in pf_keys]
    ke_every = max(1, int(round(0.004 / (P["ke_every_steps"] * P["dt_s"]))))
    return {
        "code": code,
        "code_version": rr.liggghts_version() if code == "liggghts" else rr.yade_version(),
        "case": "pour", "model": "hertz",
        "params": pour_params(code, radii0, initial),
        "packing_fraction": statistics.mean(pfs),
        "packing_fraction_runs": pfs,
        "packing_fraction_runs_labels": pf_keys,
        "packing_fraction_std": statistics.stdev(pfs) if len(pfs) > 1 else None,
        "bed_height_m": statistics.mean(hs),
        "bed_height_m_runs": hs,
        "measuring_region_m_runs": [runs[k]["measuring_region_m"] for k in pf_keys],
        "highest_sphere_top_m_runs": [runs[k]["highest_sphere_top_m"] for k in pf_keys],
        "particles_left_at_end": [runs[k]["n_final"] for k in pf_keys],
        "kinetic_energy_J": [[r[0], r[1]] for r in runs[prim]["kinetic_energy"]],
        "kinetic_energy_translational_J": [[r[0], r[2]] for r in runs[prim]["kinetic_energy"]],
        "kinetic_energy_J_run": prim,
        "kinetic_energy_J_all_runs_every_4ms": {k: [[r[0], r[1]] for r in runs[k]["kinetic_energy"][::ke_every]]
                                               for k in sorted(runs)},
        "wall_time_s": runs[prim]["wall_time_s"],
        "particle_steps_per_second": runs[prim]["particle_steps_per_second"],
        "timing_run": prim,
        "timings": {k: {"threads": v["threads"], "wall_time_s": v["wall_time_s"], "loop_time_s": v["loop_time_s"],
                        "particle_steps_per_second": v["particle_steps_per_second"]} for k, v in sorted(runs.items())},
        "machine": f"{os.cpu_count()} CPU cores, one run at a time",
        "definitions": POUR_DEFINITIONS,
    }


def pour_params(code, radii0, initial):
    """The parameters of the pour as CODE ran it."""
    P = cases.POUR
    return {
        **P, "material": cases.MAT, "n_particles": P["n"],
        "model_switches": rr.SWITCHES[(code, "hertz")],
        "walls_detail": ("LIGGGHTS: fix wall/gran ... primitive type 1 zplane/xplane/yplane (R* = r)" if code == "liggghts"
                         else "YADE: utils.wall(pos, axis, sense=0) x 5 (Mindlin uses R = r/2 on walls)"),
        "layout_rule": cases.pour_layout.__doc__.strip(),
        "initial_radii_m": radii0,
        "initial_positions_m": initial,
        "initial_velocities": "all zero (translational and angular)",
        "deck": "decks/pour_run<k>/in.liggghts + particles.data" if code == "liggghts"
                else "params.json written by cases.yade_params('pour', 'hertz', run=k) + yade_case.py",
    }


POUR_DEFINITIONS = {
    "packing_fraction": "solid volume fraction inside the measuring region, i.e. the fraction of the points of a "
                        "cell-centred grid of spacing 1e-4 m filling the region that lie inside any sphere "
                        "(final positions at t_end); mean over the runs listed in packing_fraction_runs",
    "measuring_region_m": "[[x0,x1],[y0,y1],[z0,z1]] = 2 nominal diameters (8 mm) from every side wall and from "
                          "the floor, top at bed_height - 2 diameters",
    "bed_height_m": "2 x volume-weighted mean centre height of all spheres, 2 sum(r_i^3 z_i) / sum(r_i^3) "
                    "(a uniform bed from z = 0 to H has its centroid at H/2)",
    "kinetic_energy_J": "[t_s, sum 1/2 m v^2 + 1/2 I w^2] over all spheres every 400 steps (2 ms); YADE values use "
                        "half-step (leapfrog) velocities",
    "wall_time_s": "whole process, start to exit (includes start-up, deck reading, output)",
    "particle_steps_per_second": "n_particles x n_steps / loop time (LIGGGHTS: 'Loop time' of the run; YADE: "
                                 "wall time of O.run(n, wait=True))",
    "runs": "perturbation k shifts the jitter phase (k / 7) of every sphere; radii identical in all runs",
}


def plot(docs):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, 2, figsize=(12, 4.3))
    for code, (doc, runs) in docs.items():
        for k, v in sorted(runs.items()):
            ke = v["kinetic_energy"]
            axs[0].semilogy([r[0] for r in ke[1:]], [max(r[1], 1e-16) for r in ke[1:]],
                            "-" if code == "liggghts" else "--", lw=1, label=k)
    axs[0].set_xlabel("t [s]")
    axs[0].set_ylabel("kinetic energy [J]")
    axs[0].set_title("pour: 2000 spheres, total KE")
    axs[0].legend(fontsize=7)
    labels, vals = [], []
    for code, (doc, runs) in docs.items():
        for lab, pf in zip(doc["packing_fraction_runs_labels"], doc["packing_fraction_runs"]):
            labels.append(lab)
            vals.append(pf)
    axs[1].bar(range(len(vals)), vals, color=["C0" if l.startswith("ligg") else "C1" for l in labels])
    axs[1].set_xticks(range(len(vals)))
    axs[1].set_xticklabels(labels, rotation=30, fontsize=7)
    axs[1].set_ylim(min(vals) - 0.01, max(vals) + 0.01)
    axs[1].set_ylabel("packing fraction (measuring region)")
    axs[1].set_title("packing fraction per run")
    fig.tight_layout()
    fig.savefig(os.path.join(rr.REF, "pour.png"), dpi=110)


def main(argv):
    args = [a for a in argv[1:] if a != "pour"]
    if not args or args[0] == "all":
        for code, k, th in PLAN:
            run_one(code, k, th)
        report()
    elif args[0] == "run":
        run_one(args[1], int(args[2]), int(args[3]) if len(args) > 3 else 1)
    elif args[0] == "collect":
        run_one(args[1], int(args[2]), int(args[3]), collect_only=True)
    elif args[0] == "rest":  # the YADE runs after the first
        for code, k, th in PLAN[4:]:
            run_one(code, k, th)
        report()
    elif args[0] == "report":
        report()


if __name__ == "__main__":
    main(sys.argv)
