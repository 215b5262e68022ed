"""What the fluidized bed's report takes from a run, for validation/imb/fluidized_bed.py.

The grains' mean height and the liquid's force on them per row of particles.csv (heights), the
bed's voidage from them (voidage, band_voidage), a run's outcome from its exit code, log and
summary.json (outcome, device), and its record (distil_run) distilled into
validation/imb/results/fluidized_bed.json (distil).
"""
import csv
import json
import math
import os
import re

import results as compact  # validation/imb/results.py: validation/imb/results/fluidized_bed.json
from fluidized_bed_scenes import (AVERAGE_FROM, CASES, D, FLOOR, G, GPU_CASES, HELD_AVERAGE_FROM, HELD_FROM, RHO_F,
                                  RHO_P, SCRIPT, TOP, WIDTH_X, held_grains, name, scene_steps, width_y)


# The band of the bed whose grains give its local voidage: centres 1 to 3 diameters above the
# distributor (above the layer the distributor orders, below the bed's top).
BAND = (1.0 * D, 3.0 * D)


def heights(path):
    """([(time, mean height of the grains' centres above the distributor, grains, grains whose
    centre lies in BAND, grains within a diameter of the top plane, the liquid's vertical force on
    all grains [N], buoyancy included) per output row], [x, y, z] of each grain in the last row),
    in one pass over particles.csv."""
    rows = {}
    last = (None, [])
    with open(path) as f:
        for r in csv.DictReader(f):
            t = float(r["time"])
            z = float(r["z"])
            s = rows.setdefault(t, [0.0, 0, 0, 0, 0.0])
            s[0] += z - FLOOR
            s[1] += 1
            s[2] += BAND[0] <= z - FLOOR < BAND[1]
            s[3] += z > TOP - D
            s[4] += float(r["fz"])
            if t != last[0]:
                last = (t, [])
            last[1].append([float(r["x"]), float(r["y"]), z])
    return sorted((t, s / n, n, b, top, fz) for t, (s, n, b, top, fz) in rows.items()), last[1]


def band_voidage(count, depth):
    """Voidage of BAND from the grains whose centres lie in it."""
    return 1.0 - count * math.pi / 6.0 * D**3 / (WIDTH_X * width_y(depth) * (BAND[1] - BAND[0]))


def voidage(mean_height, count, depth):
    """Voidage of a uniform bed of `count` grains whose centres average `mean_height` above the
    distributor: the bed is twice that high."""
    solids = count * math.pi / 6.0 * D**3
    return 1.0 - solids / (WIDTH_X * width_y(depth) * 2.0 * mean_height)


# lbm-server's exit status when stopped by SIGINT (validation/gpu/run.sh's time limit): outputs written.
EXIT_INTERRUPTED = 130


def simulated(folder, steps):
    """Seconds simulated in `steps` steps of the case's run."""
    return steps * json.load(open(os.path.join(folder, "summary.json")))["lattice"]["dt_s"]


def outcome(folder):
    """(ran to the end, what stopped it or None, steps completed, wall time, MLUPS)."""
    log = open(os.path.join(folder, "log.txt")).read()
    code = int(open(os.path.join(folder, "exit_code")).read())
    summary_path = os.path.join(folder, "summary.json")
    summary = json.load(open(summary_path)) if os.path.exists(summary_path) else {}
    steps = summary.get("steps_completed")
    if code == 0 and steps == summary.get("steps_requested") and scene_steps(folder) == steps:
        return True, None, steps, summary.get("wall_time_s"), summary.get("fluid_mlups")
    if code in (0, EXIT_INTERRUPTED) and steps is not None:
        reason = "stopped after %d of %d steps (%.2f s)" % (steps, scene_steps(folder), simulated(folder, steps))
        return False, reason, steps, summary.get("wall_time_s"), summary.get("fluid_mlups")
    errors = [l for l in log.splitlines() if "error" in l]
    reason = errors[-1] if errors else "exit code %d" % code
    reason = re.sub(r"^lbm-server: (error: )?", "", reason)
    reason = re.sub(r"^\S+scene\.toml: (.*?): unstable.*$", r"refused: \1", reason)
    reason = re.sub(r"(left the domain at step \d+): position.*$", r"\1 (the fluid blew up around it)", reason)
    reason = re.sub(r"(the fluid became unstable by step \d+: cell \d+ at \([^)]*\)).*$", r"\1", reason)
    return False, reason, summary.get("steps_completed"), summary.get("wall_time_s"), summary.get("fluid_mlups")


def stats(values):
    """[mean, min, max] of VALUES."""
    return [sum(values) / len(values), min(values), max(values)]


def distil(folders):
    """The records of the run FOLDERS (named as `name` or `held_name` name them, with exit_code) into the results."""
    out = {}
    for folder in folders:
        run = os.path.basename(os.path.normpath(folder))
        if not os.path.exists(os.path.join(folder, "exit_code")):
            print("%s: no exit_code (not run), not distilled" % folder)
            continue
        out[run] = distil_run(folder, run)
    compact.merge(SCRIPT, out, about="The fluidized bed: one record per run of validation/imb/fluidized_bed.py (its "
                  "outcome; the last row's grains at the top; from 0.5 s on (the held bed: 0.4 s) the voidage, that of "
                  "the band 1-3 d and the weight the liquid carries, as [mean, min, max]; the held bed's starting "
                  "voidage and largest displacement [m]; the grains where the MRT Re 200 run left them, which the "
                  "held bed holds).")


def distil_run(folder, run):
    """What the report needs of the run in FOLDER (the case RUN)."""
    done, reason, steps, wall, mlups = outcome(folder)
    rec = dict(exit_code=int(open(os.path.join(folder, "exit_code")).read()), ran_to_end=done, reason=reason,
               steps=steps, wall_time_s=wall, fluid_mlups=mlups, simulated_s=simulated(folder, steps) if done else None,
               device=device(folder))
    rows = []
    hpath = os.path.join(folder, "heights.csv")
    if os.path.exists(hpath):
        with open(hpath) as f:
            rows = list(csv.DictReader(f))
        last = rows[-1]
        rec["last_row"] = dict(time=float(last["time"]), grains=int(last["grains"]), at_top=int(last["at_top"]))
    held = run.startswith("held_")
    if held:
        start = held_grains(folder)
        rec["start_voidage"] = voidage(sum(p[2] - FLOOR for p in start) / len(start), len(start), HELD_FROM[2])
    if not (done and rows):
        return rec
    if held:
        buoyant = (RHO_P - RHO_F) * math.pi / 6.0 * D**3 * G
        ratio = [float(r["fluid_fz"]) / (len(start) * buoyant) for r in rows if float(r["time"]) >= HELD_AVERAGE_FROM]
        if ratio:
            rec["force_over_buoyant_weight"] = stats(ratio)
        with open(os.path.join(folder, "grains.csv")) as f:
            end = [[float(r[k]) for k in ("x", "y", "z")] for r in csv.DictReader(f)]
        rec["largest_displacement_m"] = max(math.dist(a, b) for a, b in zip(start, end))
        return rec
    depth = next(c[2] for c in CASES + GPU_CASES if name(*c) == run)
    late = [r for r in rows if float(r["time"]) >= AVERAGE_FROM]
    if late:
        rec["voidage"] = stats([voidage(float(r["mean_height"]), int(r["grains"]), depth) for r in late])
        rec["band_voidage"] = stats([band_voidage(int(r["in_band"]), depth) for r in late])
        if "fluid_fz" in late[0]:
            weight = int(late[0]["grains"]) * RHO_P * math.pi / 6.0 * D**3 * G
            rec["weight_carried"] = sum(float(r["fluid_fz"]) for r in late) / len(late) / weight
    if run == name(*HELD_FROM):
        with open(os.path.join(folder, "grains.csv")) as f:
            rec["last_grains"] = [[float(r[k]) for k in ("x", "y", "z")] for r in csv.DictReader(f)]
    return rec


def device(folder):
    """The Vulkan adapter the run's log names (its line "lbm-server: scene ... on <adapter> (...)")."""
    log = open(os.path.join(folder, "log.txt")).read()
    m = re.search(r"^lbm-server: scene .*? on (.+?)(?: \(|,|$)", log, re.M)
    if not m:
        return ""
    return "lavapipe CPU" if m.group(1).startswith("llvmpipe") else m.group(1).strip()
