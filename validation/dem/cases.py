"""Single source of parameters for the DEM cross-code validation (issue 4, item 7).

Everything is SI. This module
  * defines the cases (CASES / pour_layout),
  * writes the LIGGGHTS decks (decks/<case>/in.liggghts, data files) and the params.json that
    the YADE script (yade_case.py) reads, so both codes are driven by the same numbers,
  * reads the raw outputs of both codes back (trajectories, dumps) and measures the outputs.

Run it with the system python (/usr/bin/python3, numpy 1.x); run_references.py is the driver.
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
DECKS = os.path.join(HERE, "decks")

# ----------------------------------------------------------------------------------------------
# Material: glass-bead-like but softened (E = 5e7 Pa) so that contacts last ~250 us.
MAT = dict(density_kg_m3=2500.0, youngs_modulus_Pa=5.0e7, poisson_ratio=0.3,
           restitution=0.5, friction=0.3)
R0 = 0.002  # nominal sphere radius [m]


def sphere_mass(r, rho=MAT["density_kg_m3"]):
    return rho * 4.0 / 3.0 * math.pi * r ** 3


def damping_ratio(e):
    """zeta = -ln e / sqrt(ln^2 e + pi^2): a linear spring-dashpot (no clamp) with
    c = 2 zeta sqrt(m* k) rebounds with exactly e."""
    le = math.log(e)
    return -le / math.sqrt(le * le + math.pi ** 2)


M0 = sphere_mass(R0)
KN = 1.0e4                      # linear normal stiffness [N/m] (contact value)
CN = 2.0 * damping_ratio(MAT["restitution"]) * math.sqrt(M0 * KN)  # e = 0.5 for sphere-wall, m* = m
KT = 2.0 / 7.0 * KN             # linear tangential stiffness [N/m]
CT = 0.0                        # linear tangential damping [N s/m]

LINEAR = dict(kn_N_m=KN, cn_N_s_m=CN, kt_N_m=KT, ct_N_s_m=CT)


def hertz_derived(r1, r2, m1, m2, v):
    """Closed-form values of the LIGGGHTS hertz model for reference (undamped Hertz time/overlap)."""
    E, nu = MAT["youngs_modulus_Pa"], MAT["poisson_ratio"]
    Ys = 1.0 / (2 * (1 - nu ** 2) / E)
    Rs = r1 * r2 / (r1 + r2) if r2 is not None else r1
    ms = m1 * m2 / (m1 + m2) if m2 is not None else m1
    dmax = (15.0 * ms * v * v / (16.0 * Ys * math.sqrt(Rs))) ** 0.4
    tc = 2.868265699 * (ms * ms / (Rs * Ys * Ys * v)) ** 0.2
    return dict(Y_star_Pa=Ys, R_star_m=Rs, m_star_kg=ms,
                undamped_hertz_peak_overlap_m=dmax, undamped_hertz_contact_time_s=tc)


def linear_analytic(m_star):
    """Closed-form values of the linear spring-dashpot WITHOUT force clamp."""
    w0 = math.sqrt(KN / m_star)
    zeta = CN / (2 * math.sqrt(m_star * KN))
    wd = w0 * math.sqrt(1 - zeta ** 2)
    tc = math.pi / wd
    e = math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2))
    return dict(m_star_kg=m_star, damping_ratio=zeta, omega0_rad_s=w0,
                restitution_no_clamp=e, contact_time_no_clamp_s=tc)


# ----------------------------------------------------------------------------------------------
# Case 1: normal impact on a plane wall, no gravity, frictionless.
DROP = dict(
    radius_m=R0, density_kg_m3=MAT["density_kg_m3"], mass_kg=M0,
    wall="plane z = 0, normal +z, fixed, same material as the sphere",
    initial_position_m=[0.0, 0.0, R0 + 2.0e-5],  # gap 20 um -> contact starts at t = 2e-5 s
    initial_velocity_m_s=[0.0, 0.0, -1.0],
    initial_angular_velocity_rad_s=[0.0, 0.0, 0.0],
    gravity_m_s2=[0.0, 0.0, 0.0],
    friction=0.0,
    dt_s=1.0e-7, t_end_s=6.0e-4,
)

# Case 2: oblique sphere-sphere impact, no gravity, with friction.
OBLIQUE_ANGLES = [30, 60]
OBLIQUE_V_REL = 1.0   # |v1 - v2| [m/s]
OBLIQUE_GAP = 2.0e-5  # distance travelled (relative) before contact [m]


def oblique_params(angle_deg):
    th = math.radians(angle_deg)
    u = [math.cos(th), math.sin(th), 0.0]
    s = OBLIQUE_GAP
    c1 = [-0.5 * s * u[0], -0.5 * s * u[1], 0.0]
    c2 = [2 * R0 + 0.5 * s * u[0], 0.5 * s * u[1], 0.0]
    v1 = [0.5 * OBLIQUE_V_REL * u[0], 0.5 * OBLIQUE_V_REL * u[1], 0.0]
    v2 = [-x for x in v1]
    return dict(
        angle_deg=angle_deg,
        radius_m=[R0, R0], density_kg_m3=MAT["density_kg_m3"], mass_kg=[M0, M0],
        initial_position_m=[c1, c2], initial_velocity_m_s=[v1, v2],
        initial_angular_velocity_rad_s=[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
        note=("line of centres at first touch is +x (sphere 1 -> sphere 2); relative velocity v1 - v2 "
              "makes angle_deg with it in the x-y plane; first touch at t = gap / |v1 - v2| = 2e-5 s"),
        gravity_m_s2=[0.0, 0.0, 0.0], friction=MAT["friction"],
        dt_s=1.0e-7, t_end_s=6.0e-4,
    )


# Case 3: pour into a box.
POUR = dict(
    n=2000, box_m=[0.04, 0.04], lattice_spacing_m=0.0047, lattice_n_xy=8, lattice_origin_m=0.0025,
    jitter_m=1.0e-4, radius_mean_m=R0, radius_halfwidth_rel=0.1,
    gravity_m_s2=[0.0, 0.0, -9.81], dt_s=5.0e-6, t_end_s=float(os.environ.get("POUR_T_END_S", "0.6")), ke_every_steps=400,
    friction=MAT["friction"], model="hertz",
    walls="floor z = 0 (normal +z); side walls x = 0, x = 0.04, y = 0, y = 0.04; open top; all fixed planes, same material",
)
POUR_RUNS = [0, 1, 2]


def _frac(x):
    return x - math.floor(x)


def pour_layout(k):
    """Deterministic (seed-free) layout for perturbation run k.
    Radii (same for every k): r_i = r0 (1 + 0.1 (2 frac(i phi) - 1)), phi = golden ratio conjugate.
    Positions: 8 x 8 lattice per layer, spacing a = 4.7 mm, origin 2.5 mm, layer l = i // 64
    at z = 2.5 mm + l a, plus jitter j (2 frac(i sqrt(c) + k / 7) - 1), c = 2, 3, 5 for x, y, z, j = 0.1 mm.
    All values rounded to 1e-7 m (radii to 1e-8 m); the rounded numbers are the exact inputs."""
    P = POUR
    n, a, o, J = P["n"], P["lattice_spacing_m"], P["lattice_origin_m"], P["jitter_m"]
    nxy = P["lattice_n_xy"]
    phi = (math.sqrt(5) - 1) / 2
    radii, pos = [], []
    for i in range(n):
        r = P["radius_mean_m"] * (1 + P["radius_halfwidth_rel"] * (2 * _frac(i * phi) - 1))
        radii.append(round(r, 8))
        l, rem = divmod(i, nxy * nxy)
        iy, ix = divmod(rem, nxy)
        jit = [J * (2 * _frac(i * math.sqrt(c) + k / 7.0) - 1) for c in (2, 3, 5)]
        pos.append([round(o + ix * a + jit[0], 7), round(o + iy * a + jit[1], 7),
                    round(o + l * a + jit[2], 7)])
    return radii, pos


# ----------------------------------------------------------------------------------------------
# LIGGGHTS deck writers
def _lig_header(xlo, xhi, ylo, yhi, zlo, zhi, skin):
    return f"""units si
atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
processors 1 1 1
"""


def _lig_materials(model, friction, limit_force=False):
    E, nu, e = MAT["youngs_modulus_Pa"], MAT["poisson_ratio"], MAT["restitution"]
    s = f"""fix m1 all property/global youngsModulus peratomtype {E!r}
fix m2 all property/global poissonsRatio peratomtype {nu!r}
fix m3 all property/global coefficientRestitution peratomtypepair 1 {e!r}
fix m4 all property/global coefficientFriction peratomtypepair 1 {friction!r}
"""
    if model == "linear":
        s += f"""fix m5 all property/global kn peratomtypepair 1 {KN!r}
fix m6 all property/global kt peratomtypepair 1 {KT!r}
fix m7 all property/global gamman_abs peratomtypepair 1 {CN!r}
fix m8 all property/global gammat_abs peratomtypepair 1 {CT!r}
"""
        mdl = "model hooke/stiffness tangential history"
        opts = " absolute_damping on" + (" limitForce on" if limit_force else "")
    else:
        mdl = "model hertz tangential history"
        opts = ""
    return s, mdl, opts


def write_liggghts_drop(model, variant=""):
    P = DROP
    d = os.path.join(DECKS, f"drop_{model}{variant}")
    os.makedirs(d, exist_ok=True)
    mats, mdl, opts = _lig_materials(model, P["friction"], limit_force=(variant == "_limitforce"))
    x, y, z = P["initial_position_m"]
    vx, vy, vz = P["initial_velocity_m_s"]
    nsteps = int(round(P["t_end_s"] / P["dt_s"]))
    deck = _lig_header(0, 0, 0, 0, 0, 0, 0) + f"""region domain block -0.01 0.01 -0.01 0.01 -0.001 0.01 units box
create_box 1 domain
neighbor 0.0005 bin
neigh_modify delay 0
{mats}pair_style gran {mdl}{opts}
pair_coeff * *
timestep {P['dt_s']!r}
fix wall all wall/gran {mdl} primitive type 1 zplane 0.0{opts}
create_atoms 1 single {x!r} {y!r} {z!r} units box
set atom 1 diameter {2 * P['radius_m']!r} density {P['density_kg_m3']!r}
velocity all set {vx!r} {vy!r} {vz!r} units box
fix integr all nve/sphere
dump traj all custom 1 traj.dump id x y z vx vy vz omegax omegay omegaz
dump_modify traj format "%d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g" sort id
run {nsteps}
"""
    open(os.path.join(d, "in.liggghts"), "w").write(deck)
    return d


def write_liggghts_oblique(model, angle):
    P = oblique_params(angle)
    d = os.path.join(DECKS, f"oblique_{model}_{angle}")
    os.makedirs(d, exist_ok=True)
    mats, mdl, opts = _lig_materials(model, P["friction"])
    nsteps = int(round(P["t_end_s"] / P["dt_s"]))
    atoms = ""
    for i in range(2):
        x, y, z = P["initial_position_m"][i]
        vx, vy, vz = P["initial_velocity_m_s"][i]
        atoms += f"create_atoms 1 single {x!r} {y!r} {z!r} units box\n"
    for i in range(2):
        vx, vy, vz = P["initial_velocity_m_s"][i]
        atoms += (f"set atom {i + 1} diameter {2 * P['radius_m'][i]!r} density {P['density_kg_m3']!r}\n"
                  f"group g{i + 1} id {i + 1}\nvelocity g{i + 1} set {vx!r} {vy!r} {vz!r} units box\n")
    deck = _lig_header(0, 0, 0, 0, 0, 0, 0) + f"""region domain block -0.01 0.02 -0.01 0.01 -0.01 0.01 units box
create_box 1 domain
neighbor 0.0005 bin
neigh_modify delay 0
{mats}pair_style gran {mdl}{opts}
pair_coeff * *
timestep {P['dt_s']!r}
{atoms}fix integr all nve/sphere
dump traj all custom 1 traj.dump id x y z vx vy vz omegax omegay omegaz
dump_modify traj format "%d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g" sort id
run {nsteps}
"""
    open(os.path.join(d, "in.liggghts"), "w").write(deck)
    return d


def write_liggghts_pour(k):
    P = POUR
    d = os.path.join(DECKS, f"pour_run{k}")
    os.makedirs(d, exist_ok=True)
    radii, pos = pour_layout(k)
    L = P["box_m"]
    rho = MAT["density_kg_m3"]
    lines = [f"LIGGGHTS data file: pour run {k} (written by cases.py)", "",
             f"{P['n']} atoms", "1 atom types", "",
             f"-0.001 {L[0] + 0.001!r} xlo xhi", f"-0.001 {L[1] + 0.001!r} ylo yhi", "-0.001 0.2 zlo zhi", "",
             "Atoms", ""]
    for i, (r, p) in enumerate(zip(radii, pos)):
        lines.append(f"{i + 1} 1 {2 * r!r} {rho!r} {p[0]!r} {p[1]!r} {p[2]!r}")
    open(os.path.join(d, "particles.data"), "w").write("\n".join(lines) + "\n")
    mats, mdl, opts = _lig_materials(P["model"], P["friction"])
    nsteps = int(round(P["t_end_s"] / P["dt_s"]))
    g = P["gravity_m_s2"]
    deck = _lig_header(0, 0, 0, 0, 0, 0, 0) + f"""read_data particles.data
neighbor 0.0008 bin
neigh_modify delay 0
{mats}pair_style gran {mdl}{opts}
pair_coeff * *
timestep {P['dt_s']!r}
fix floor all wall/gran {mdl} primitive type 1 zplane 0.0{opts}
fix wx0 all wall/gran {mdl} primitive type 1 xplane 0.0{opts}
fix wx1 all wall/gran {mdl} primitive type 1 xplane {L[0]!r}{opts}
fix wy0 all wall/gran {mdl} primitive type 1 yplane 0.0{opts}
fix wy1 all wall/gran {mdl} primitive type 1 yplane {L[1]!r}{opts}
fix gravi all gravity {math.sqrt(sum(c * c for c in g))!r} vector 0.0 0.0 -1.0
fix integr all nve/sphere
compute ket all ke
compute ker all erotate/sphere
variable t equal time
variable ket equal c_ket
variable ker equal c_ker
variable n equal count(all)
fix out all print {P['ke_every_steps']} "${{t}} ${{ket}} ${{ker}} ${{n}}" file ke.txt screen no title "# t KE_trans KE_rot n"
thermo 20000
dump fin all custom {nsteps} final.dump id radius x y z vx vy vz
dump_modify fin format "%d %.10g %.10g %.10g %.10g %.6g %.6g %.6g"
run {nsteps}
"""
    open(os.path.join(d, "in.liggghts"), "w").write(deck)
    return d


# ----------------------------------------------------------------------------------------------
# params.json for YADE (same numbers)
def yade_params(case, model, **kw):
    p = dict(case=case, model=model, material=MAT, linear=LINEAR)
    if case == "drop":
        p.update(DROP)
        p["variant"] = kw.get("variant", "")
    elif case == "oblique":
        p.update(oblique_params(kw["angle"]))
    elif case == "pour":
        p.update(POUR)
        radii, pos = pour_layout(kw["run"])
        p.update(radii_m=radii, positions_m=pos, run=kw["run"])
    return p


# ----------------------------------------------------------------------------------------------
# measurements
def crossings(t, d):
    """Sub-step zero crossings of the overlap d(t) (linear interpolation between samples):
    returns (t_start, t_end, first_step_index, last_step_index) of the first contact."""
    i0 = next(i for i in range(len(d)) if d[i] > 0)
    i1 = next((i for i in range(i0, len(d)) if d[i] <= 0), None)
    ts = t[i0 - 1] + (t[i0] - t[i0 - 1]) * (0 - d[i0 - 1]) / (d[i0] - d[i0 - 1])
    if i1 is None:
        return ts, float("nan"), i0, len(d) - 1
    te = t[i1 - 1] + (t[i1] - t[i1 - 1]) * (0 - d[i1 - 1]) / (d[i1] - d[i1 - 1])
    return ts, te, i0, i1 - 1


def packing_fraction(radii, pos, region, h=1.0e-4):
    """Solid volume fraction in an axis-aligned box region = [[x0,x1],[y0,y1],[z0,z1]]:
    fraction of the points of the cell-centred grid of spacing h (1e-4 m) that lie inside a sphere."""
    import numpy as np
    (x0, x1), (y0, y1), (z0, z1) = region
    nx, ny, nz = int(round((x1 - x0) / h)), int(round((y1 - y0) / h)), int(round((z1 - z0) / h))
    hx, hy, hz = (x1 - x0) / nx, (y1 - y0) / ny, (z1 - z0) / nz
    occ = np.zeros((nx, ny, nz), dtype=bool)
    xs = x0 + (np.arange(nx) + 0.5) * hx
    ys = y0 + (np.arange(ny) + 0.5) * hy
    zs = z0 + (np.arange(nz) + 0.5) * hz
    for r, (cx, cy, cz) in zip(radii, pos):
        if cx + r < x0 or cx - r > x1 or cy + r < y0 or cy - r > y1 or cz + r < z0 or cz - r > z1:
            continue
        ia, ib = np.searchsorted(xs, cx - r), np.searchsorted(xs, cx + r)
        ja, jb = np.searchsorted(ys, cy - r), np.searchsorted(ys, cy + r)
        ka, kb = np.searchsorted(zs, cz - r), np.searchsorted(zs, cz + r)
        if ia >= ib or ja >= jb or ka >= kb:
            continue
        dx = (xs[ia:ib] - cx) ** 2
        dy = (ys[ja:jb] - cy) ** 2
        dz = (zs[ka:kb] - cz) ** 2
        occ[ia:ib, ja:jb, ka:kb] |= (dx[:, None, None] + dy[None, :, None] + dz[None, None, :]) < r * r
    return float(occ.mean())


def bed_measures(radii, pos):
    """Bed height H = 2 x (volume-weighted mean sphere-centre height) (a uniform bed from z = 0 to H
    has its centroid at H/2). Measuring region: 2 nominal diameters (8 mm) from every side wall and
    from the floor, up to H - 2 diameters."""
    import numpy as np
    r = np.asarray(radii)
    p = np.asarray(pos)
    V = r ** 3
    H = 2.0 * float((V * p[:, 2]).sum() / V.sum())
    D = 2 * POUR["radius_mean_m"]
    L = POUR["box_m"]
    region = [[2 * D, L[0] - 2 * D], [2 * D, L[1] - 2 * D], [2 * D, H - 2 * D]]
    phi = packing_fraction(radii, pos, region)
    top = float((p[:, 2] + r).max())
    return dict(bed_height_m=H, measuring_region_m=region, packing_fraction=phi, highest_sphere_top_m=top)


def read_liggghts_dump(path, dt):
    """Parse a LIGGGHTS 'dump custom' trajectory (id x y z vx vy vz omegax omegay omegaz, sorted by id).
    Returns rows [t, x1, y1, z1, vx1, ..., wz1, x2, ...] (same layout as yade_case.py's traj.txt)."""
    rows = []
    with open(path) as f:
        lines = f.read().split("\n")
    i = 0
    while i < len(lines):
        if lines[i].startswith("ITEM: TIMESTEP"):
            step = int(lines[i + 1])
            n = int(lines[i + 3])
            j = i + 4
            while not lines[j].startswith("ITEM: ATOMS"):
                j += 1
            row = [step * dt]
            for a in range(n):
                row += [float(x) for x in lines[j + 1 + a].split()[1:]]
            rows.append(row)
            i = j + 1 + n
        else:
            i += 1
    return rows
