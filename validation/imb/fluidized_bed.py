#!/usr/bin/env python3
"""The fluidized bed of validation/scenes/fluidized-bed.toml at Re 200 and 400 with each operator.

The seed paper's bed (BGK, 10 cells per diameter) ran at Re 200 and diverged at Re 400. For each
case this script writes the scene with its operator and inflow (Re = U d / nu) into the ignored work
folder validation/imb/work/fluidized_bed/<operator>_Re<re>/, runs `lbm-server run` there (or records why
the scene was refused), keeps summary.json, the log and the grains' mean height per output row, distils
what the report needs (the run's outcome, the bed's voidage and the weight the liquid carries) into the
case's record in validation/imb/results/fluidized_bed.json, and writes validation/imb/FLUIDIZED_BED.md from
the records: whether each case ran to its end, and where it did, the expanded bed's voidage against
Richardson & Zaki (1954).

    python3 validation/imb/fluidized_bed.py                  # every case (about an hour on lavapipe)
    python3 validation/imb/fluidized_bed.py mrt_Re400        # one case
    python3 validation/imb/fluidized_bed.py --report         # only the report, from the results
    python3 validation/imb/fluidized_bed.py distil DIR       # DIR/<case>/ (folders as a run leaves them) into the results
    python3 validation/imb/fluidized_bed.py held             # the bed held still at 6 and 9 cells, and with the
                                                             # superposition term at 6 (25 min)
    python3 validation/imb/fluidized_bed.py held-superposed  # only the last (4 min)
    python3 validation/imb/fluidized_bed.py scenes DIR       # write the GPU cases' scenes (validation/gpu/)
    python3 validation/imb/fluidized_bed.py held-scenes DIR  # the held bed's GPU scenes
    python3 validation/imb/fluidized_bed.py import DIR       # take a GPU batch's runs into the results

LBM_SERVER names another lbm-server (as for ten_cate.py).
"""

import argparse
import csv
import json
import math
import os
import re
import shutil
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import results as compact  # noqa: E402
import ten_cate_analysis  # noqa: E402  (validation/imb/ten_cate.py's parts: a drag law's terminal velocity)
import ten_cate_runs  # noqa: E402  (lbm-server, LBM_SERVER and how a scene is run)
import ten_cate_scenes  # noqa: E402  (the superposition solid term's table)

ROOT = os.path.dirname(os.path.dirname(HERE))
SCENE = os.path.join(ROOT, "validation", "scenes", "fluidized-bed.toml")
SCRIPT = "fluidized_bed"
OUT = compact.work(SCRIPT)
REPORT = os.path.join(HERE, "FLUIDIZED_BED.md")

# The scene's physics (validation/scenes/fluidized-bed.toml).
RHO_F, MU, RHO_P, D, G = 1000.0, 1.48e-3, 2650.0, 0.003, 9.81
NU = MU / RHO_F
WIDTH_X = 0.030  # m; the slab's depth is DEPTH diameters (4 in the scene)
FLOOR = 0.0075  # the distributor plane, m
TOP = 0.0645  # the top plane, m
MACH = 0.1
CELLS = 6  # cells per diameter of the scene (dx 0.5 mm)
SIM_TIME = 0.75  # s of each run
AVERAGE_FROM = 0.5  # s: the voidage is averaged over the rows from here on
# The fastest liquid expected, over the superficial velocity: the liquid between the grains.
SPEED_OVER_U = 0.3 / 0.1973

# (operator, Re, slab depth in diameters, cells per diameter): the scene's slab, and Re 200 in one
# twice as deep (the grains in 7 rows across instead of 3) to see what the walls do.
CASES = [
    ("mrt", 400, 4, CELLS),
    ("mrt", 200, 4, CELLS),
    ("trt", 400, 4, CELLS),
    ("trt", 200, 4, CELLS),
    ("bgk", 400, 4, CELLS),
    ("bgk", 200, 4, CELLS),
    ("trtb", 400, 4, CELLS),
    ("trtb", 200, 4, CELLS),
    ("mrt", 200, 8, CELLS),
    ("mrts", 200, 4, CELLS),
    ("mrtp", 200, 4, CELLS),
    ("mrtp", 200, 4, 9),
    ("mrtp", 200, 4, 12),
    ("mrty", 200, 4, CELLS),
    ("mrtf", 200, 4, CELLS),
    ("mrty", 200, 8, CELLS),
]
# Finer grids, for a GPU (validation/gpu/run.sh; too slow for lavapipe): whether the bed's excess
# expansion at 6 cells is the grid's (the held sphere's drag at 8 cells is 15-25% above Schiller-
# Naumann at Re 100-400 in validation/lbm/REPORT.md, "Stability near tau = 1/2"; but a periodic
# array carrying the bed's weight has the same drag at 6 cells as at 24, the report's "drag in a
# bed"). In the order the batch runs them: the slab with periodic sides at 15 cells (6, 9 and 12 run
# on lavapipe: without the walls, how the excess falls with the grid), the seed's 10 cells at Re 200
# and 400, the deep slab,
# the seed's operator (BGK) at its Re 200, then 15 cells; the superposition term at 10 cells
# (whether the halved excess it gives at 6 cells holds on a finer grid) before Re 400 at 15.
GPU_CASES = [
    ("mrtp", 200, 4, 15),
    ("mrt", 200, 4, 10),
    ("mrt", 400, 4, 10),
    ("mrt", 200, 8, 10),
    ("bgk", 200, 4, 10),
    ("mrt", 200, 4, 15),
    ("mrts", 200, 4, 10),
    ("mrt", 400, 4, 15),
]
ROWS_ACROSS = {4: 3, 8: 7}


# "trtb": TRT with tau- bounded (lattice.max_tau_minus), which held a sphere's wake where BGK held.
MAX_TAU_MINUS = 1.0


# "mrts": MRT with the superposition solid term (ten_cate_scenes.SUPERPOSITION; docs/imb.md, "The
# solid collision"), which drags a lone sphere at Re 200-300 less than Noble & Torczynski's.


# "mrtp": MRT with the slab's side faces periodic for the liquid and the grains (no side walls, no
# side planes): whether the walls make the bed's excess expansion; "mrty": periodic along y only
# (the walls 10 diameters apart kept, those 4 apart gone): which walls.
PERIODIC_AXES = {"mrtp": "xy", "mrty": "y"}
# A side plane of the scene: its normal along x (index 0) or y (index 1).
SIDE_PLANE = r"\[\[dem\.plane\]\]\npoint = \[[^\n]*\]\nnormal = \[%s, 0\.0\]\n"
SIDE_NORMALS = {"x": r"-?1\.0, 0\.0", "y": r"0\.0, -?1\.0"}


def periodic(operator):
    """The axes along which the case's sides are periodic ("" for walls all round)."""
    return PERIODIC_AXES.get(operator, "")


def with_sides(text, operator):
    """The scene TEXT with the case's periodic sides: their planes gone, their faces periodic."""
    faces = ""
    for axis in periodic(operator):
        text, n = re.subn(SIDE_PLANE % SIDE_NORMALS[axis], "", text)
        if n != 2:
            raise SystemExit("%s: %d side planes normal to %s, expected 2" % (SCENE, n, axis))
        faces += "".join('%s_%s = "periodic"\n' % (axis, end) for end in ("min", "max"))
    return text.replace("[lattice.faces]\n", "[lattice.faces]\n" + faces, 1)


# "mrtf": the walls all round, but frictionless for the grains (the side planes of a material
# whose friction is 0; the grains' own material is the default): whether the walls' share is the
# grains rubbing on them.
SMOOTH_SIDES = "mrtf"
MATERIALS = '[[dem.material]]\nname = "sand"\n[[dem.material]]\nname = "smooth"\nfriction = 0.0\n\n'


def with_smooth_sides(text, operator):
    """The scene TEXT with its four side planes frictionless for the grains, for SMOOTH_SIDES."""
    if operator != SMOOTH_SIDES:
        return text
    for axis in "xy":
        text, n = re.subn("(%s)" % (SIDE_PLANE % SIDE_NORMALS[axis]), r'\1material = "smooth"\n', text)
        if n != 2:
            raise SystemExit("%s: %d side planes normal to %s, expected 2" % (SCENE, n, axis))
    return text.replace("[[dem.insert]]", MATERIALS + "[[dem.insert]]", 1)


def label(operator):
    if operator == SMOOTH_SIDES:
        return "MRT, walls frictionless for the grains"
    if periodic(operator) == "xy":
        return "MRT, periodic sides"
    if periodic(operator) == "y":
        return "MRT, periodic along y (walls 10 d apart)"
    if operator == "trtb":
        return "TRT (tau- <= %g)" % MAX_TAU_MINUS
    if operator == "mrts":
        return "MRT, superposition"
    return operator.upper()


def name(operator, re_, depth, cells=CELLS):
    return "%s_Re%d" % (operator, re_) + ("" if depth == 4 else "_D%d" % depth) + ("" if cells == CELLS else "_N%d" % cells)


def width_y(depth):
    return depth * D


def inflow(re_):
    """Superficial velocity U [m/s] of particle Reynolds number re_ = U d / nu."""
    return re_ * NU / D


def scene_text(operator, re_, depth, cells=CELLS):
    """The scene with this operator, this inflow, a velocity scale in proportion, this grid and the
    steps of SIM_TIME."""
    u = inflow(re_)
    scale = SPEED_OVER_U * u
    dx = D / cells
    dt = time_step(re_, cells)
    text = open(SCENE).read()
    subs = [
        (r'^operator = .*$', 'operator = "%s"' % operator[:3] + ("\nmax_tau_minus = %g" % MAX_TAU_MINUS if operator == "trtb" else "")),
        (r"^velocity_scale = .*$", "velocity_scale = %.4f                # m/s: %.2f U" % (scale, SPEED_OVER_U)),
        (r"^dx = .*$", "dx = %.10g                       # m: %d cells per grain diameter" % (dx, cells)),
        (r"^steps = .*$", "steps = %d                         # coupled steps (%.2f s)" % (round(SIM_TIME / dt), SIM_TIME)),
        (r"^z_min = .*$", 'z_min = { type = "velocity_inlet", velocity = [0.0, 0.0, %.4f] } # m/s: Re %d' % (u, re_)),
        (r"^max = \[0\.030, 0\.012, ", "max = [0.030, %g, " % width_y(depth)),
        (r"^point = \[0\.0, 0\.012, 0\.0\]", "point = [0.0, %g, 0.0]" % width_y(depth)),
        (r"^count = \[9, 3, 8\]", "count = [9, %d, 8]" % ROWS_ACROSS[depth]),
    ]
    for pattern, new in subs:
        text, n = re.subn(pattern, new, text, count=1, flags=re.M)
        if n != 1:
            raise SystemExit("%s: no line matches %r" % (SCENE, pattern))
    text = with_smooth_sides(with_sides(text, operator), operator)
    return text + (ten_cate_scenes.SUPERPOSITION if operator == "mrts" else "")


def time_step(re_, cells):
    """dt [s] of the scene at Re with this many cells per diameter (as lbm-server derives it)."""
    return MACH / math.sqrt(3.0) * (D / cells) / (SPEED_OVER_U * inflow(re_))


def lattice_tau(re_, cells):
    """tau of the scene at Re with this many cells per diameter (as lbm-server derives it)."""
    return 0.5 + 3.0 * NU * time_step(re_, cells) / (D / cells) ** 2


def settling_reynolds():
    """(Archimedes number, Re_t of one grain settling alone by Schiller-Naumann's drag)."""
    ar = G * D**3 * (RHO_P / RHO_F - 1.0) / NU**2
    u_t = ten_cate_analysis.terminal_velocity(RHO_F, MU, RHO_P, D, "sn", 0.1)
    return ar, u_t * D / NU


def richardson_zaki(re_, depth):
    """(n, voidage unbounded, voidage with the wall term) of Richardson & Zaki (1954) at Re:
    U / u_i = eps^n with n = (4.7 + 0.41 Re_t^0.75) / (1 + 0.175 Re_t^0.75) (Rowe 1987) and
    log10 u_i = log10 u_t - d / D, D the narrow width of the slab."""
    _, re_t = settling_reynolds()
    n = (4.7 + 0.41 * re_t**0.75) / (1.0 + 0.175 * re_t**0.75)
    ratio = re_ / re_t
    walled = ratio / 10.0 ** (-D / width_y(depth))
    return n, ratio ** (1.0 / n), (walled ** (1.0 / n) if walled < 1.0 else float("nan"))


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


def keep(out, work, code):
    """What the work folder keeps of a run whose outputs are in WORK: its exit code, summary.json, the
    grains' mean height and the liquid's force on them per row (heights.csv) and where the grains
    were in the last row (grains.csv, what `held` holds)."""
    with open(os.path.join(out, "exit_code"), "w") as f:
        f.write("%d\n" % code)
    if os.path.exists(os.path.join(work, "summary.json")):
        shutil.copy(os.path.join(work, "summary.json"), os.path.join(out, "summary.json"))
    particles = os.path.join(work, "particles.csv")
    if os.path.exists(particles):
        rows, last = heights(particles)
        with open(os.path.join(out, "heights.csv"), "w") as f:
            f.write("time,mean_height,grains,in_band,at_top,fluid_fz\n")
            for t, h, n, b, top, fz in rows:
                f.write("%.6g,%.6g,%d,%d,%d,%.6g\n" % (t, h, n, b, top, fz))
        with open(os.path.join(out, "grains.csv"), "w") as f:
            f.write("x,y,z\n")
            for p in last:
                f.write("%.8g,%.8g,%.8g\n" % tuple(p))


# The bed held still: the grains where the MRT Re 200 run left them (its grains.csv, in its record)
# held in place (no gravity, density HELD_DENSITY: they move less than a hundredth of a cell), the
# same inflow, HELD_TIME s; the liquid's force on them over their buoyant weight, averaged from
# HELD_AVERAGE_FROM s on. Whether a grain's drag in this bed is the moving grains' doing or the
# arrangement's and the grid's, by resolution (6 and 9 cells here, 12 and 18 on a GPU).
HELD_FROM = ("mrt", 200, 4, CELLS)
HELD_CELLS = [6, 9]
GPU_HELD_CELLS = [12, 18]
# The same held with the superposition solid term ("mrts"), at these cells per diameter.
HELD_SUPERPOSED_CELLS = [6]
HELD_TIME = 0.6
HELD_AVERAGE_FROM = 0.4
HELD_DENSITY = 1.0e9
HELD_GAP = 3e-6  # m left between held grains, and between a grain and a plane


def held_name(cells, operator=HELD_FROM[0]):
    return "held_%s_N%d" % (name(operator, *HELD_FROM[1:]), cells)


def separated(points, depth):
    """The grains of POINTS pushed apart where they touch (contacts overlap by microns; a scene
    refuses overlapping spheres) and into the slab, HELD_GAP from each other and the planes."""
    points = [list(p) for p in points]
    r = D / 2.0
    bounds = [(0.0, WIDTH_X), (0.0, width_y(depth)), (FLOOR, TOP)]
    for _ in range(100):
        moved = False
        for i, a in enumerate(points):
            for b in points[i + 1:]:
                d = math.dist(a, b)
                if d < 2.0 * r + HELD_GAP:
                    push = (2.0 * r + 1.5 * HELD_GAP - d) / 2.0
                    for k in range(3):
                        u = (a[k] - b[k]) / d
                        a[k] += push * u
                        b[k] -= push * u
                    moved = True
        for p in points:
            for k, (low, high) in enumerate(bounds):
                p[k] = min(max(p[k], low + r + HELD_GAP), high - r - HELD_GAP)
        if not moved:
            return points
    raise SystemExit("held bed: grains still overlap after 100 passes")


def held_grains(folder):
    """The grains a held scene holds ([x, y, z] of each of its spheres)."""
    text = open(os.path.join(folder, "scene.toml")).read()
    return [[float(v) for v in m.split(",")] for m in re.findall(r"^position = \[([^\]]*)\]", text, re.M)]


def held_scene_text(cells, operator=HELD_FROM[0]):
    """HELD_FROM's scene at this many cells per diameter with its last row's grains held (with
    OPERATOR's fluid: "mrts" for the superposition term)."""
    _, re_, depth, _ = HELD_FROM
    grains = separated(compact.runs(SCRIPT)[name(*HELD_FROM)]["last_grains"], depth)
    text = scene_text(operator, re_, depth, cells)
    spheres = "".join(
        "[[particles.sphere]]\nposition = [%.8g, %.8g, %.8g]\nradius = %g\n" % (*p, D / 2.0) for p in grains
    )
    subs = [
        (r"^gravity = .*$", "gravity = [0.0, 0.0, 0.0]            # held: the grains carry no weight"),
        (r"^density = 2650\.0.*$", "density = %g                     # kg/m^3: held in place" % HELD_DENSITY),
        (r"^steps = .*$", "steps = %d                         # coupled steps (%.2f s)" % (round(HELD_TIME / time_step(re_, cells)), HELD_TIME)),
        (r"(?s)^\[\[dem\.insert\]\].*?(?=^\[\[dem\.plane\]\])", spheres + "\n"),
    ]
    for pattern, new in subs:
        text, n = re.subn(pattern, new, text, count=1, flags=re.M)
        if n != 1:
            raise SystemExit("%s: no line matches %r" % (SCENE, pattern))
    text = with_sides(text, operator)
    return text


def run_held(cells, operator=HELD_FROM[0]):
    out = os.path.join(OUT, held_name(cells, operator))
    code, work = ten_cate_runs.run_scene(out, held_scene_text(cells, operator))
    keep(out, work, code)
    shutil.rmtree(work, ignore_errors=True)
    distil([out])


def tenneti(phi, re_):
    """Tenneti, Garg & Subramaniam (2011): the mean force on a sphere of a fixed random array, the
    mean pressure gradient's share included, over 3 pi mu d U (U superficial, Re = U d / nu); the
    same law as lbm-server's validate/bed_drag.rs."""
    eps = 1.0 - phi
    return ((1.0 + 0.15 * re_**0.687) / eps**3 + 5.81 * phi / eps**3 + 0.48 * phi ** (1.0 / 3.0) / eps**4
            + phi**3 * re_ * (0.95 + 0.61 * phi**3 / eps**2))


def buoyant_weight(re_):
    """A grain's buoyant weight over 3 pi mu d U at Re (U = Re nu / d)."""
    return (RHO_P - RHO_F) * G * math.pi / 6.0 * D**3 / (3.0 * math.pi * MU * D * inflow(re_))


def tenneti_voidage(re_):
    """The voidage at which Tenneti et al.'s random arrays carry a grain's buoyant weight at Re
    (bisection)."""
    low, high = 0.4, 0.99
    for _ in range(60):
        mid = 0.5 * (low + high)
        if tenneti(1.0 - mid, re_) > buoyant_weight(re_):
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)


# The command that makes a case's run on a GPU (the batch of validation/gpu/: prepare.sh writes the
# scenes, run.sh runs them on the device machine, import.sh takes them into the results).
GPU_BATCH = "bash validation/gpu/prepare.sh"


def held_rows(opening):
    """The held bed's report lines; its rows of the summary appended to OPENING."""
    operator, re_, depth, _ = HELD_FROM
    ar, re_t = settling_reynolds()
    lines = [
        "",
        "## The bed held still",
        "",
        "The grains where the %s Re %d run left them (its last row, in the record of %s, pushed apart"
        % (label(operator), re_, name(*HELD_FROM)),
        "to %g um where they touched) held in place (no gravity and density %g kg/m^3 in the scene), the"
        % (HELD_GAP * 1e6, HELD_DENSITY),
        "same inflow (Re %d), %.2f s; the liquid's vertical force on all of them over their buoyant weight," % (re_, HELD_TIME),
        "mean and range from %.2f s on (the free bed's own, from %.2f s, in the table above: the liquid" % (HELD_AVERAGE_FROM, AVERAGE_FROM),
        "carries the weight of a fluidized bed). Reference: Tenneti, Garg & Subramaniam (2011), fixed",
        "random arrays resolved (solid fraction 0.1-0.5, Re up to 300), at the held bed's voidage (from",
        "its grains' mean height, as above) and Re %d; Richardson & Zaki's bed at that voidage stands at" % re_,
        "the Re given. Largest displacement: how far a held grain moved over the run.",
        "",
        "| cells per d | tau | solid term | outcome | steps | wall time [s] | MLUPS | device | force / buoyant weight (range) | Tenneti | error | voidage | Richardson-Zaki Re | largest displacement [cells] |",
        "|---:|---:|---|---|---:|---:|---:|---|---|---:|---:|---:|---:|---:|",
    ]
    runs = [(cells, operator) for cells in HELD_CELLS + GPU_HELD_CELLS] + [(cells, "mrts") for cells in HELD_SUPERPOSED_CELLS]
    records = compact.runs(SCRIPT)
    for cells, held_operator in runs:
        rec = records.get(held_name(cells, held_operator))
        if rec is None:
            continue
        done, columns = run_columns(rec)
        eps = rec["start_voidage"]
        expected = 3.0 * math.pi * re_ * tenneti(1.0 - eps, re_) / (ar * math.pi / 6.0)
        n_rz, _, _ = richardson_zaki(re_, depth)
        re_rz = re_t * eps**n_rz
        force = error = moved = ""
        if "force_over_buoyant_weight" in rec:
            mean = rec["force_over_buoyant_weight"][0]
            force = "%.3f (%.3f-%.3f)" % tuple(rec["force_over_buoyant_weight"])
            error = "%+.0f%%" % (100.0 * (mean / expected - 1.0))
        if "largest_displacement_m" in rec:
            moved = "%.2g" % (rec["largest_displacement_m"] / (D / cells))
        command = GPU_BATCH if cells in GPU_HELD_CELLS else \
            "python3 validation/imb/fluidized_bed.py %s" % ("held-superposed" if held_operator == "mrts" else "held")
        opening.append(("held bed, %d cells per d, %s term: liquid's force / buoyant weight" % (
            cells, "superposition" if held_operator == "mrts" else "Noble-Torczynski"),
            "%.3f, Tenneti et al. (2011)" % expected, force.split(" ")[0] or columns[0],
            error.replace("%", " %") or "-", command))
        lines.append(
            "| %d | %.4f | %s | %s | %s | %s | %s | %s | %s | %.3f | %s | %.3f | %.0f | %s |"
            % (
                cells,
                lattice_tau(re_, cells),
                "superposition" if held_operator == "mrts" else "Noble-Torczynski",
                *columns,
                force,
                expected,
                error,
                eps,
                re_rz,
                moved,
            )
        )
    return lines


def run(operator, re_, depth, cells=CELLS):
    out = os.path.join(OUT, name(operator, re_, depth, cells))
    code, work = ten_cate_runs.run_scene(out, scene_text(operator, re_, depth, cells))
    keep(out, work, code)
    shutil.rmtree(work, ignore_errors=True)
    distil([out])


def plan_line(path, depth, cells):
    """The plan's line of the GPU scene in PATH: its name, cells, steps and cell-steps."""
    grid = [round(x / (D / cells)) for x in (WIDTH_X, width_y(depth), 0.072)]
    steps = scene_steps(path)
    cell_steps = grid[0] * grid[1] * grid[2] * steps
    return "%s %dx%dx%d steps %d cell-steps %.3g" % (os.path.basename(path), *grid, steps, cell_steps)


def write_scenes(folder):
    """The GPU cases' scenes, FOLDER/bed_<name>/scene.toml, and one line each on stdout (name,
    cells, steps, cell-steps) for validation/gpu/prepare.sh's plan."""
    for case in GPU_CASES:
        _, _, depth, cells = case
        text = scene_text(*case)
        path = os.path.join(folder, "bed_" + name(*case))
        os.makedirs(path, exist_ok=True)
        with open(os.path.join(path, "scene.toml"), "w") as f:
            f.write(text)
        print(plan_line(path, depth, cells))


def write_held_scenes(folder):
    """The held bed's GPU scenes, FOLDER/bed_held_<...>/scene.toml, one line each as write_scenes."""
    depth = HELD_FROM[2]
    for cells in GPU_HELD_CELLS:
        path = os.path.join(folder, "bed_" + held_name(cells))
        os.makedirs(path, exist_ok=True)
        with open(os.path.join(path, "scene.toml"), "w") as f:
            f.write(held_scene_text(cells))
        print(plan_line(path, depth, cells))


def import_runs(folder):
    """FOLDER/bed_<name>/ of a GPU batch (scene.toml, log.txt, exit_code, summary.json,
    particles.csv) into the work folder as `run` leaves its runs, then into the results."""
    done = []
    for entry in sorted(os.listdir(folder)):
        src = os.path.join(folder, entry)
        if not entry.startswith("bed_") or not os.path.exists(os.path.join(src, "exit_code")):
            print("%s: no exit_code (not run), not imported" % entry)
            continue
        out = os.path.join(OUT, entry[len("bed_"):])
        os.makedirs(out, exist_ok=True)
        for f in ("scene.toml", "log.txt"):
            shutil.copy(os.path.join(src, f), os.path.join(out, f))
        keep(out, src, int(open(os.path.join(src, "exit_code")).read()))
        print("%s: imported into %s" % (entry, out))
        done.append(out)
    distil(done)


# lbm-server's exit status when stopped by SIGINT (validation/gpu/run.sh's time limit): outputs written.
EXIT_INTERRUPTED = 130


def scene_steps(folder):
    """The steps of SIM_TIME the case's scene asks for."""
    return int(re.search(r"^steps = (\d+)", open(os.path.join(folder, "scene.toml")).read(), re.M).group(1))


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


def run_columns(rec):
    """(ran to the end, the report's outcome, steps, wall time, MLUPS and device columns) of a run's record."""
    done, reason, steps, wall, mlups = (rec[k] for k in ("ran_to_end", "reason", "steps", "wall_time_s", "fluid_mlups"))
    text = "ran %.2f s" % rec["simulated_s"] if done else reason.replace("|", "/")
    return done, [
        text,
        steps if steps is not None else "",
        "%.0f" % wall if wall else "",
        "%.2f" % mlups if mlups else "",
        rec["device"],
    ]


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


def report():
    ar, re_t = settling_reynolds()
    lines = [
        "# A fluidized bed at Re 200 and 400 by operator (the seed paper's section 5)",
        "",
        "Written by `python3 validation/imb/fluidized_bed.py --report` from `results/fluidized_bed.json`",
        "(runs on lavapipe, this repository's 2-core CPU machine, shared with other runs: read wall time and",
        "MLUPS as +-50%; the device column names the others). The scene:",
        "validation/scenes/fluidized-bed.toml, 216 sand grains (d = 3 mm, density ratio 2.65) in",
        "water-like liquid (nu = %.3g m^2/s), a slab 10 x 4 x 24 diameters (60 x 24 x 144 cells; one case" % NU,
        "8 diameters deep with 504 grains, 7 rows across; five with periodic sides, one of them 8 deep, one with walls frictionless for the grains), 6 cells per diameter (9 and 12; 10 and 15 on a GPU:",
        "the device column), uniform inflow through the floor at U = Re nu / d, a pressure",
        "outlet at the top (the equilibrium outflow, docs/lbm.md), DEM planes 2.5 diameters from both.",
        "Each case runs %.2f s; lattice.velocity_scale is %.2f U (the liquid between the grains), Mach" % (SIM_TIME, SPEED_OVER_U),
        "0.1, so tau = 0.5017 at Re 400 and 0.5034 at Re 200 (tau - 1/2 grows as the cells per diameter).",
        "The seed's bed (BGK, 10 cells per diameter)",
        "ran at Re 200 and diverged at Re 400.",
        "",
        "Voidage: the grains' centres average h above the distributor, a uniform bed is 2h high, voidage",
        "= 1 - N V_p / (A 2h), averaged over the rows from %.2f s on (mean and range); \"1-3 d\": the" % AVERAGE_FROM,
        "grains whose centres lie 1 to 3 diameters above the distributor, over that band's volume. Reference:",
        "Richardson & Zaki (1954), U / u_i = eps^n, with the grain's settling velocity from",
        "Schiller-Naumann (Archimedes number %.3g: Re_t = %.0f, u_t = %.3f m/s) and n from Rowe" % (ar, re_t, re_t * NU / D),
        "(1987); \"walled\" divides u_t by 10^(d/D) with D the slab's 4 diameters (Richardson & Zaki's",
        "wall term, made for tubes: for a slab it is an estimate). \"Grains at the top\": centres within a",
        "diameter of the top plane in the last row kept (a bed lifted against it is no longer fluidized).",
        "\"Weight the liquid carries\": its vertical force on the grains (buoyancy included) over their",
        "weight, mean of the rows from %.2f s on (1: the bed is fluidized, not resting on the planes)." % AVERAGE_FROM,
        "\"Tenneti\": the voidage at which Tenneti, Garg & Subramaniam's (2011) fixed random arrays carry",
        "a grain's buoyant weight at that Re; \"drag / Tenneti's\": the liquid's force on the grains over",
        "what their law gives at the measured voidage and Re (validation/lbm/REPORT.md's random arrays at",
        "voidage 0.76: 1.6-1.8 at 6-12 cells per diameter). \"Periodic sides\": the slab's four side",
        "faces periodic for the liquid and the grains, no side walls or planes.",
        "",
        "| case | Re | slab depth [d] | cells per d | tau | U [m/s] | outcome | steps | wall time [s] | MLUPS | device | grains at the top, last row | weight the liquid carries | voidage (range) | voidage 1-3 d (range) | Richardson-Zaki | walled | error | Tenneti | drag / Tenneti's |",
        "|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---|---|---:|---|---|---:|---:|---:|---:|---:|",
    ]
    records = compact.runs(SCRIPT)
    opening = []
    for operator, re_, depth, cells in CASES + GPU_CASES:
        rec = records.get(name(operator, re_, depth, cells))
        if rec is None:
            continue
        done, columns = run_columns(rec)
        n, eps_rz, eps_walled = richardson_zaki(re_, depth)
        measured = band = error = top = carried = excess = ""
        if "last_row" in rec:
            top = "%s of %s (%.2f s)" % (rec["last_row"]["at_top"], rec["last_row"]["grains"], rec["last_row"]["time"])
        if "voidage" in rec:
            mean = rec["voidage"][0]
            measured = "%.3f (%.3f-%.3f)" % tuple(rec["voidage"])
            error = "%+.1f%%" % (100.0 * (mean / eps_rz - 1.0))
            band = "%.3f (%.3f-%.3f)" % tuple(rec["band_voidage"])
            if "weight_carried" in rec:
                share = rec["weight_carried"]
                carried = "%.3f" % share
                excess = "%.2f" % (share * buoyant_weight(re_) / tenneti(1.0 - mean, re_))
        gpu = (operator, re_, depth, cells) in GPU_CASES
        opening.append(("%s, Re %d, slab %d d, %d cells per d: bed voidage" % (label(operator), re_, depth, cells),
                        "%.3f, Richardson-Zaki" % eps_rz, measured.split(" ")[0] or columns[0],
                        error.replace("%", " %") or "-",
                        GPU_BATCH if gpu else "python3 validation/imb/fluidized_bed.py %s" % name(operator, re_, depth, cells)))
        lines.append(
            "| %s | %d | %d | %d | %.4f | %.4f | %s | %s | %s | %s | %s | %s | %s | %s | %s | %.3f | %s | %s | %.3f | %s |"
            % (
                label(operator),
                re_,
                depth,
                cells,
                lattice_tau(re_, cells),
                inflow(re_),
                *columns,
                top,
                carried,
                measured,
                band,
                eps_rz,
                "-" if periodic(operator) else "%.3f" % eps_walled,
                error,
                tenneti_voidage(re_),
                excess,
            )
        )
    lines.append("")
    lines.append("Error: the measured voidage against Richardson-Zaki without the wall term. What these runs")
    lines.append("found (the ramp, the outflow without backflow, the bed lifted at Re 400, BGK and TRT with")
    lines.append("tau- <= 1 blowing up in the bed where they held one sphere): docs/imb.md, \"Stability near")
    lines.append("tau = 1/2\". BGK was refused below tau 0.51 until 2026-12-03. The liquid carries the bed's")
    lines.append("weight: it is fluidized, its grains feel too much drag. The grid hardly changes that: MRT at")
    lines.append("Re 200 expands the bed to voidage 0.761, 0.757 and 0.747 at 6, 10 and 15 cells per diameter")
    lines.append("(+30.1%, +29.4%, +27.8%; 10 and 15 on an NVIDIA H200, 2026-12-04), and at 10 cells Re 400")
    lines.append("lifts the bed against the top plane and blows up (step 11293, 0.65 s) and BGK at Re 200 blows")
    lines.append("up (step 1534) as at 6. Held still (below) the grains carry their buoyant weight at 6, 9 and 12")
    lines.append("cells alike (1.07, 1.05, 1.01): not their motion, and not the grid. With the superposition")
    lines.append("solid term (\"MRT, superposition\", coupling.solid_collision; docs/imb.md \"The solid")
    lines.append("collision\"), which drags every sphere 10-20% less, the bed at 6 cells expands 16.2% more than")
    lines.append("Richardson & Zaki instead of 30.1%, and held it carries 0.77 of its weight instead of 1.07;")
    lines.append("but that term also drags 9-15% too little in Stokes flow, where the default is within 1%.")
    lines.append("A simple cubic array at")
    lines.append("voidage 0.76 carries the weight at Re 476-491 at 6 to 24 cells (spheres in line shelter each")
    lines.append("other); a random array in a periodic box at Re 252-266 at 6 to 12 cells, where Tenneti et al.'s")
    lines.append("random arrays need 361, though in Stokes flow it converges to theirs, and at 279 at 18 cells (one")
    lines.append("placement): its excess falls with the grid, as a lone sphere's at Re 200-300 does, +25-29% above")
    lines.append("Schiller & Naumann at 6 cells, +6-7% at 16 (validation/lbm/REPORT.md, \"drag in a bed\", \"a random")
    lines.append("array at the fluidized bed's voidage\" and \"a held sphere at the fluidized bed's Reynolds")
    lines.append("numbers\"; docs/imb.md).")
    lines.append("Without the side walls (\"MRT, periodic sides\": the slab's four side faces periodic for the")
    lines.append("liquid and the grains, 2026-12-05) the bed at Re 200 expands to voidage 0.709 / 0.718 / 0.719 at")
    lines.append("6 / 9 / 12 cells (+21.2 / +22.7 / +23.0%), its grains dragged 1.84 / 1.94 / 1.96 times Tenneti et")
    lines.append("al.'s at that voidage, where the walled slab's are 2.48 at 6 cells (2.55 twice as deep, 2.29 at")
    lines.append("15): about a third of the excess expansion is the walls' (Richardson & Zaki's wall term, made for")
    lines.append("tubes, expects more of them), the rest the drag that the random arrays show at these grids, 1.6-1.8")
    lines.append("times Tenneti's, not falling from 6 to 12 cells (1.5 at 18 cells). Which walls: periodic along y")
    lines.append("only (\"MRT, periodic along y\", the walls 10 diameters apart kept, those 4 apart gone) the bed")
    lines.append("expands to 0.733 at 6 cells (+25.3%, drag 2.11 times Tenneti's): each pair of walls makes about")
    lines.append("half of the walls' share. Twice as deep and periodic along y, 0.732 (+25.2%): the pair 8")
    lines.append("diameters apart adds 6.2 points (31.4 - 25.2), the pair 4 apart 4.8, the pair 10 apart 4.1; a pair")
    lines.append("of walls adds 4-6 points whatever its distance, not a confinement that falls as 1/width. Nor is it")
    lines.append("a circulation the walls drive: both beds circulate (grains' vz from 0.4 s on, by distance from the")
    lines.append("x faces, a throwaway rerun: walled, -4 to -8 mm/s within 3 d of the walls, +12 mm/s beyond 4 d;")
    lines.append("periodic, -9 to -16 mm/s within 3 d of the faces, +17 mm/s beyond), the periodic one no less. Nor")
    lines.append("is it the grains rubbing on")
    lines.append("the walls: with the walls frictionless for them (\"MRT, walls frictionless\") the bed expands to")
    lines.append("0.761 at 6 cells (+30.2%), as with friction. The periodic slab at 15 cells is in the GPU batch.")
    lines += held_rows(opening)
    lines[2:2] = [compact.summary(opening, "python3 validation/imb/fluidized_bed.py --report",
                                  "`%s` writes the scenes of the GPU batch (validation/gpu/)." % GPU_BATCH), ""]
    with open(REPORT, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def main():
    if sys.argv[1:2] == ["held"]:
        for cells in HELD_CELLS:
            run_held(cells)
        for cells in HELD_SUPERPOSED_CELLS:
            run_held(cells, "mrts")
        report()
        return
    if sys.argv[1:2] == ["held-superposed"]:
        for cells in HELD_SUPERPOSED_CELLS:
            run_held(cells, "mrts")
        report()
        return
    if sys.argv[1:2] in (["scenes"], ["held-scenes"], ["import"], ["distil"]):
        if len(sys.argv) != 3:
            raise SystemExit("usage: fluidized_bed.py %s DIR" % sys.argv[1])
        if sys.argv[1] == "scenes":
            write_scenes(sys.argv[2])
            return
        if sys.argv[1] == "held-scenes":
            write_held_scenes(sys.argv[2])
            return
        if sys.argv[1] == "distil":
            distil([os.path.join(sys.argv[2], entry) for entry in sorted(os.listdir(sys.argv[2]))])
        else:
            import_runs(sys.argv[2])
        report()
        return
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("cases", nargs="*", help="cases to run (e.g. mrt_Re400); default: all")
    parser.add_argument("--report", action="store_true", help="only write the report from the results")
    args = parser.parse_args()
    if not args.report:
        wanted = args.cases or [name(*c) for c in CASES]
        for case in CASES + GPU_CASES:
            if name(*case) in wanted:
                run(*case)
    report()


if __name__ == "__main__":
    main()
