# YADE side of the DEM cross-code validation. Run inside yade:
#   yade -jN -n -x yade_case.py <params.json> <outdir>
# params.json is written by cases.py (same numbers as the LIGGGHTS decks).
# Model switches used (see README): linear -> ViscElMat + Law2_ScGeom_ViscElPhys_Basic (material kn, cn, ks, cs
# are 2x the contact value because two identical materials combine in series);
# hertz -> FrictMat + Ip2_FrictMat_FrictMat_MindlinPhys(en=e, es=e) + Law2_ScGeom_MindlinPhys_Mindlin.
# NewtonIntegrator(damping=0). No numerical damping anywhere.
import json
import math
import os
import sys
import time

P = json.load(open(sys.argv[1]))
OUT = sys.argv[2]
os.makedirs(OUT, exist_ok=True)
model = P["model"]
mat = P["material"]
lin = P["linear"]
mu = P["friction"]

if model == "linear":
    M = ViscElMat(kn=2 * lin["kn_N_m"], cn=2 * lin["cn_N_s_m"], ks=2 * lin["kt_N_m"], cs=2 * lin["ct_N_s_m"],
                  frictionAngle=math.atan(mu), density=mat["density_kg_m3"])
    ip2 = Ip2_ViscElMat_ViscElMat_ViscElPhys()
    law = Law2_ScGeom_ViscElPhys_Basic()
else:
    M = FrictMat(young=mat["youngs_modulus_Pa"], poisson=mat["poisson_ratio"], frictionAngle=math.atan(mu),
                 density=mat["density_kg_m3"])
    ip2 = Ip2_FrictMat_FrictMat_MindlinPhys(en=mat["restitution"], es=mat["restitution"])
    law = Law2_ScGeom_MindlinPhys_Mindlin()
mid = O.materials.append(M)

rec = []
g = P["gravity_m_s2"]

if P["case"] == "drop":
    if P.get("variant") == "_bigsphere":
        Rb = 100.0
        O.bodies.append(sphere((0, 0, -Rb), Rb, material=mid, fixed=True))
    else:
        O.bodies.append(wall(0.0, axis=2, sense=1, material=mid))
    b = O.bodies.append(sphere(P["initial_position_m"], P["radius_m"], material=mid))
    O.bodies[b].state.vel = Vector3(*P["initial_velocity_m_s"])
    ids = [b]
elif P["case"] == "oblique":
    ids = []
    for i in range(2):
        b = O.bodies.append(sphere(P["initial_position_m"][i], P["radius_m"][i], material=mid))
        O.bodies[b].state.vel = Vector3(*P["initial_velocity_m_s"][i])
        ids.append(b)
else:  # pour
    L = P["box_m"]
    for pos, axis in ((0.0, 2), (0.0, 0), (L[0], 0), (0.0, 1), (L[1], 1)):
        O.bodies.append(wall(pos, axis=axis, sense=0, material=mid))
    ids = [O.bodies.append(sphere(p, r, material=mid)) for p, r in zip(P["positions_m"], P["radii_m"])]


def record():
    # called after NewtonIntegrator of iteration O.iter: positions belong to time O.time + dt,
    # velocities (leapfrog) to O.time + dt/2
    t = O.time + O.dt
    row = [t]
    for i in ids:
        s = O.bodies[i].state
        row += list(s.pos) + list(s.vel) + list(s.angVel)
    rec.append(row)


def record_ke():
    t = O.time + O.dt
    ket = ker = 0.0
    for i in ids:
        s = O.bodies[i].state
        ket += 0.5 * s.mass * s.vel.squaredNorm()
        ker += 0.5 * (s.inertia[0] * s.angVel[0] ** 2 + s.inertia[1] * s.angVel[1] ** 2 + s.inertia[2] * s.angVel[2] ** 2)
    rec.append([t, ket, ker, len(ids)])


if P["case"] == "pour":
    runner = PyRunner(command="record_ke()", iterPeriod=P["ke_every_steps"], initRun=False)
    bo1 = [Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]
else:
    runner = PyRunner(command="record()", iterPeriod=1, initRun=True)
    bo1 = [Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]

O.engines = [
    ForceResetter(),
    InsertionSortCollider(bo1),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()], [ip2], [law]),
    NewtonIntegrator(damping=0.0, gravity=Vector3(*g)),
    runner,
]
O.dt = P["dt_s"]
nsteps = int(round(P["t_end_s"] / P["dt_s"]))

# initial state (t = 0)
if P["case"] == "pour":
    rec.append([0.0, 0.0, 0.0, len(ids)])
else:
    row = [0.0]
    for i in ids:
        s = O.bodies[i].state
        row += list(s.pos) + list(s.vel) + list(s.angVel)
    rec.append(row)

t0 = time.time()
O.run(nsteps, True)
loop = time.time() - t0

with open(os.path.join(OUT, "traj.txt"), "w") as f:
    for row in rec:
        f.write(" ".join(repr(float(x)) for x in row) + "\n")
info = dict(loop_time_s=loop, steps=nsteps, n_particles=len(ids), threads=O.numThreads,
            yade_version=version)
if P["case"] == "pour":
    info["final"] = [[O.bodies[i].shape.radius] + list(O.bodies[i].state.pos) for i in ids]
json.dump(info, open(os.path.join(OUT, "info.json"), "w"))
print("YADE_DONE", loop)
