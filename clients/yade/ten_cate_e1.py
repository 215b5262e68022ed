# Ten Cate et al. 2002, case E1, with YADE as the DEM of the coupled run: YADE builds the sphere
# (and any other particles) from the scene file, the box's faces as its walls, and couples.
#
#   lbm-server run validation/scenes/ten-cate-e1.toml --dem external     # DEM service: RUN
#   PYTHONPATH=IOX:clients/python:clients/yade yade -n -x clients/yade/ten_cate_e1.py --service RUN [--scene SCENE]
#
# IOX: the folder where iceoryx2 for Debian's python is installed (README.md beside this file).
# A YADE script runs through execfile: __file__ is /usr/bin/yade, sys.argv[0] is this script.
import argparse
import math
import os
import sys

import lbmdem_scene  # clients/python and clients/yade on PYTHONPATH (README.md)
import lbmdem_yade

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))

ap = argparse.ArgumentParser(prog="ten_cate_e1.py",
                             description="YADE as the DEM of a coupled lbm-server run")
ap.add_argument("--service", default=os.environ.get(lbmdem_yade.RUN_ENV),
                help="run name printed by lbm-server (default: $LBMDEM_RUN)")
ap.add_argument("--scene", default=os.path.join(HERE, "..", "..", "validation", "scenes",
                                                "ten-cate-e1.toml"),
                help="the run's scene file (default: validation/scenes/ten-cate-e1.toml)")
ap.add_argument("--timeout", type=float, default=10.0,
                help="longest wait for a live but silent fluid server [s] (default 10)")
args = ap.parse_args(sys.argv[1:])

scene = lbmdem_scene.Scene.load(args.scene)
materials = {}
for m in scene.materials.values():
    # Hertz-Mindlin with the scene's restitution (YADE's Thornton damping, docs: dem-reference-codes)
    materials[m.name] = O.materials.append(FrictMat(young=m.young_modulus, poisson=m.poisson_ratio,
                                                    frictionAngle=math.atan(m.friction),
                                                    density=m.density, label=m.name))
for p in scene.particles:
    b = O.bodies.append(sphere(p.position, p.radius, material=materials[p.material]))
    O.bodies[b].state.vel = Vector3(*p.velocity)
    O.bodies[b].state.angVel = Vector3(*p.angular_velocity)
# The domain's faces are YADE's walls (the fluid box is closed in E1); added after the spheres, so
# that body i is scene particle i.
wall_material = materials[scene.particle_material]
for axis in range(3):
    for at, sense in ((scene.domain_min[axis], 1), (scene.domain_max[axis], -1)):
        O.bodies.append(wall(at, axis=axis, sense=sense, material=wall_material))

restitution = scene.material(None).restitution
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                    [Ip2_FrictMat_FrictMat_MindlinPhys(en=restitution, es=restitution)],
                    [Law2_ScGeom_MindlinPhys_Mindlin()]),
    NewtonIntegrator(damping=0.0, gravity=Vector3(*scene.gravity)),
]
# YADE steps of at most half the P-wave time step, a whole number per fluid step.
done = lbmdem_yade.couple(args.service, scene=args.scene, max_dt=0.5 * PWaveTimeStep(),
                          timeout_s=args.timeout)
z = O.bodies[0].state
print(f"ten_cate_e1: {done.ending} after {done.steps} steps ({done.substeps} YADE steps each); "
      f"sphere 0 at z = {z.pos[2]:.6g} m, vz = {z.vel[2]:.6g} m/s", flush=True)
