"""The Ten Cate et al. (2002) cases and their scenes, for validation/imb/ten_cate.py.

The sphere, the four fluids (E1-E4), the experiment's box, the default Mach number and collision
operator; the lattice numbers of a case at N cells per diameter in a box (lattice_numbers); the name
of a run's folder (run_dir) and back (spec_of); the scene of a run, written from
validation/scenes/ten-cate-e1.toml (write_scene).
"""
import math
import os
import re

import results as compact  # validation/imb/results.py: the work folder


HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
TEMPLATE = os.path.join(ROOT, "validation", "scenes", "ten-cate-e1.toml")


RUNS = compact.work("ten_cate")


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


DIR_RE = re.compile(r"(E\d)_N([0-9p]+)(?:_M([0-9p]+))?(?:_W([0-9p]+)_H([0-9p]+))?(?:_(bgk|mrt|trts|trt))?$")


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
