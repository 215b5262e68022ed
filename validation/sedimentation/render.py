#!/usr/bin/env python3
"""Seed Fig. 3-style views of a sedimentation run (validation/scenes/sedimentation-*.toml) and its
fronts against the seed's description (section 3.2: the centre falls first, the particles near the
walls are carried up).

    python3 validation/sedimentation/render.py RUN [--png FILE] [--panels 4] [--json FILE]

RUN is a run's output folder (lbm-server run SCENE --out RUN): its particles.csv (the columns
step,time,id,x,y,z are read; the GPU batch's compact copy has only those) and scene.toml (the copy
lbm-server leaves there; --scene names another). Writes a PNG: side views (x-z) of the slab one
particle spacing thick through the box's centre plane (y = W/2) at --panels times from the first
output to the last, each particle a disc of its diameter coloured by its initial height, and beside
them the fronts over time. Prints the fronts as a table (and writes them to --json):

- centre: the particles whose initial (x, y) lie within W/6 of the box's axis on both axes (the
  middle ninth of its cross-section); walls: those that start within W/10 of a side wall
  (or one spacing, where that is more: the outer ring at least);
- mean dz: their mean displacement since the first output, in particle diameters d;
- lowest: the lowest particle centre of each group, in d above the floor;
- risen: the share of the group above its initial height; rise max: the highest rise, in d;
- time in Stokes times t_s = d / v_s, v_s = (rho_p - rho_f) g d^2 / (18 mu) (one particle alone).

Needs numpy and matplotlib (requirements.txt).
"""

import argparse
import json
import math
import os
import tomllib

import numpy as np

CENTRE = 1 / 6   # centre: |x - W/2| and |y - W/2| below this fraction of the width W
WALLS = 1 / 10   # walls: within this fraction of W of a side wall (at least one spacing)


def load_scene(path):
    """The numbers the views and fronts need from the scene: box, particle, fluid, gravity."""
    with open(path, "rb") as f:
        s = tomllib.load(f)
    insert = s["dem"]["insert"][0]
    radius = insert["radius"]
    radius = radius if isinstance(radius, float) else sum(radius) / 2
    g = math.sqrt(sum(a * a for a in s.get("gravity", [0.0, 0.0, -9.81])))
    mu, rho_f = s["fluid"]["dynamic_viscosity"], s["fluid"]["density"]
    d = 2 * radius
    v_s = (s["particles"]["density"] - rho_f) * g * d * d / (18 * mu)
    lo, hi = s["domain"]["min"], s["domain"]["max"]
    return {
        "name": s.get("name", os.path.basename(path)),
        "size": [hi[a] - lo[a] for a in range(3)],
        "min": lo,
        "d": d,
        "spacing": insert["spacing"],
        "count": insert["count"],
        "v_s": v_s,
        "t_s": d / v_s,
        "re": rho_f * v_s * d / mu,
    }


def load_particles(path):
    """{step: (time, ids, xyz)} of particles.csv, each step's rows sorted by id."""
    with open(path) as f:
        header = f.readline().strip().split(",")
    cols = [header.index(c) for c in ("step", "time", "id", "x", "y", "z")]
    data = np.loadtxt(path, delimiter=",", skiprows=1, usecols=cols, ndmin=2)
    frames = {}
    for step in np.unique(data[:, 0]):
        rows = data[data[:, 0] == step]
        rows = rows[np.argsort(rows[:, 2])]
        frames[int(step)] = (rows[0, 1], rows[:, 2].astype(int), rows[:, 3:6])
    ids0 = frames[min(frames)][1]
    for step in [s for s in frames if not np.array_equal(frames[s][1], ids0)]:
        print("render.py: step %d left out: it holds other particles than the first output" % step)
        del frames[step]
    return frames


def groups(scene, xyz0):
    """Boolean masks (centre, walls) of the particles by their initial horizontal position."""
    w = scene["size"][0]
    h = xyz0[:, :2] - np.array(scene["min"][:2])
    centre = np.all(np.abs(h - w / 2) < CENTRE * w, axis=1)
    walls = np.min(np.minimum(h, w - h), axis=1) < max(WALLS * w, scene["spacing"])
    if not (centre.any() and walls.any()):
        raise SystemExit("render.py: no particle starts in the centre or near the walls")
    return centre, walls


def fronts(scene, frames):
    """One row per output step: the fronts of the centre and wall groups (module docstring)."""
    steps = sorted(frames)
    xyz0 = frames[steps[0]][2]
    centre, walls = groups(scene, xyz0)
    d, floor = scene["d"], scene["min"][2]
    rows = []
    for step in steps:
        t, _, xyz = frames[step]
        dz = (xyz[:, 2] - xyz0[:, 2]) / d
        row = {"step": step, "time": t, "t_over_ts": t / scene["t_s"]}
        for name, mask in (("centre", centre), ("walls", walls)):
            row[name + "_mean_dz"] = float(dz[mask].mean())
            row[name + "_lowest"] = float((xyz[mask, 2].min() - floor) / d)
            row[name + "_risen"] = float((dz[mask] > 0).mean())
            row[name + "_rise_max"] = float(dz[mask].max())
        rows.append(row)
    return rows, int(centre.sum()), int(walls.sum())


def print_fronts(scene, rows, n_centre, n_walls):
    print(
        "%s: d = %.3g m, v_s = %.3g m/s (Re %.3g), t_s = d / v_s = %.4g s; centre %d particles, "
        "walls %d" % (scene["name"], scene["d"], scene["v_s"], scene["re"], scene["t_s"], n_centre, n_walls)
    )
    print("| step | t [s] | t / t_s | centre mean dz [d] | walls mean dz [d] | centre lowest [d] "
          "| walls lowest [d] | walls risen | walls rise max [d] |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print("| %d | %.4g | %.2f | %+.2f | %+.2f | %.2f | %.2f | %.0f%% | %+.2f |" % (
            r["step"], r["time"], r["t_over_ts"], r["centre_mean_dz"], r["walls_mean_dz"],
            r["centre_lowest"], r["walls_lowest"], 100 * r["walls_risen"], r["walls_rise_max"]))


def panel_steps(frames, panels):
    """`panels` output steps spread evenly in time from the first output to the last."""
    steps = sorted(frames)
    times = np.array([frames[s][0] for s in steps])
    wanted = np.linspace(times[0], times[-1], panels)
    return sorted({steps[int(np.argmin(np.abs(times - t)))] for t in wanted})


def side_view(ax, scene, frame, z0, norm):
    """The slab one spacing thick through y = W/2, each particle a disc of its diameter."""
    from matplotlib.collections import EllipseCollection

    t, _, xyz = frame
    lo = scene["min"]
    slab = np.abs(xyz[:, 1] - lo[1] - scene["size"][1] / 2) < scene["spacing"] / 2
    order = np.argsort(xyz[slab, 1])
    mm = 1e3
    offsets = (xyz[slab][order][:, [0, 2]] - np.array([lo[0], lo[2]])) * mm
    d = scene["d"] * mm
    discs = EllipseCollection(
        d, d, 0.0, units="xy", offsets=offsets, offset_transform=ax.transData,
        cmap="viridis", norm=norm, linewidths=0)
    discs.set_array(z0[slab][order])
    ax.add_collection(discs)
    ax.set_xlim(0, scene["size"][0] * mm)
    ax.set_ylim(0, scene["size"][2] * mm)
    ax.set_aspect("equal")
    ax.set_title("t = %.3g s (%.2f t_s)" % (t, t / scene["t_s"]), fontsize=9)
    ax.tick_params(labelsize=7)
    return discs


def fronts_plot(ax, scene, rows):
    t = [r["t_over_ts"] for r in rows]
    ax.plot(t, [r["centre_mean_dz"] for r in rows], "C3-", label="centre: mean dz")
    ax.plot(t, [r["walls_mean_dz"] for r in rows], "C0-", label="walls: mean dz")
    ax.plot(t, [r["walls_rise_max"] for r in rows], "C0--", label="walls: highest rise")
    ax.axhline(0, color="0.6", lw=0.6)
    ax.set_xlabel("t / t_s  (t_s = d / v_s = %.3g s)" % scene["t_s"], fontsize=8)
    ax.set_ylabel("displacement [d]", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=7, loc="lower left")


def render(scene, frames, rows, png, panels):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize

    steps = panel_steps(frames, panels)
    first = frames[min(frames)]
    z0 = (first[2][:, 2] - scene["min"][2]) / scene["size"][2]
    norm = Normalize(0.5, 1.0)
    fig = plt.figure(figsize=(1.9 * len(steps) + 3.4, 5.4), layout="constrained")
    grid = fig.add_gridspec(1, len(steps) + 1, width_ratios=[1] * len(steps) + [1.8])
    views = [fig.add_subplot(grid[0, k]) for k in range(len(steps))]
    for k, (ax, step) in enumerate(zip(views, steps)):
        discs = side_view(ax, scene, frames[step], z0, norm)
        ax.set_xlabel("x [mm]", fontsize=8)
        if k == 0:
            ax.set_ylabel("z [mm]", fontsize=8)
    bar = fig.colorbar(discs, ax=views, location="bottom", fraction=0.04, aspect=40)
    bar.set_label("initial height / box height", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    fronts_plot(fig.add_subplot(grid[0, -1]), scene, rows)
    n = scene["count"]
    fig.suptitle("%s: %d x %d x %d spheres settling (Re %.2g), slab through the centre plane y = W/2"
                 % (scene["name"], n[0], n[1], n[2], scene["re"]), fontsize=10)
    fig.savefig(png, dpi=90, pil_kwargs={"optimize": True})
    print("wrote %s (%d bytes)" % (png, os.path.getsize(png)))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("run", help="a run's output folder (particles.csv, scene.toml)")
    p.add_argument("--scene", help="the scene file (default RUN/scene.toml)")
    p.add_argument("--png", help="the picture (default RUN/sedimentation.png)")
    p.add_argument("--panels", type=int, default=4, help="side views (default 4)")
    p.add_argument("--json", help="also write the fronts here")
    a = p.parse_args()
    scene = load_scene(a.scene or os.path.join(a.run, "scene.toml"))
    frames = load_particles(os.path.join(a.run, "particles.csv"))
    rows, n_centre, n_walls = fronts(scene, frames)
    print_fronts(scene, rows, n_centre, n_walls)
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"scene": scene, "centre": n_centre, "walls": n_walls, "fronts": rows}, f, indent=1)
    render(scene, frames, rows, a.png or os.path.join(a.run, "sedimentation.png"), a.panels)


if __name__ == "__main__":
    main()
