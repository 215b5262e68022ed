"""The fluidized bed's cases and their scenes, for validation/imb/fluidized_bed.py.

The scene's physics (validation/scenes/fluidized-bed.toml), the cases (operator, Re, slab depth,
cells per diameter; GPU_CASES for the GPU batch) and what their operators change in the scene
(periodic or frictionless sides, tau- bounded, the superposition solid term); a case's name,
inflow, time step and tau; its scene (scene_text); the bed held still (HELD_*, held_scene_text);
and the GPU batch's scenes with a line of its plan each (write_scenes, write_held_scenes).
"""
import math
import os
import re

import results as compact  # validation/imb/results.py: the held bed's grains from the results
import ten_cate_scenes  # validation/imb/ten_cate.py's parts: the superposition solid term's table


HERE = os.path.dirname(os.path.abspath(__file__))


ROOT = os.path.dirname(os.path.dirname(HERE))
SCENE = os.path.join(ROOT, "validation", "scenes", "fluidized-bed.toml")
SCRIPT = "fluidized_bed"


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


def scene_steps(folder):
    """The steps of SIM_TIME the case's scene asks for."""
    return int(re.search(r"^steps = (\d+)", open(os.path.join(folder, "scene.toml")).read(), re.M).group(1))


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
