
# UCS of a JCFpm-bonded sphere packing between two rigid platens (written by
# benchmarks/ucs_throughput.py); prints one JSON line with the timing.
import json, time
from yade import pack, utils
from yade.wrapper import *
R = 0.0001
W, H, D = 0.0076563563011602465, 0.015312712602320493, 0.0006000000000000001
mat = O.materials.append(JCFpmMat(young=60e9, poisson=0.25, frictionAngle=0.52,
                                  density=2650.0, tensileStrength=50e6, cohesion=100e6))
sp = pack.SpherePack()
sp.makeCloud((0, 0, 0), (W, H, D), rMean=R, rRelFuzz=0.25, num=5038, seed=1)
ids = sp.toSimulation(material=mat)
wmat = O.materials.append(FrictMat(young=60e9, poisson=0.25, frictionAngle=0.0,
                                   density=2650.0))
lo = O.bodies.append(utils.wall(0.0, axis=1, sense=1, material=wmat))
hi = O.bodies.append(utils.wall(H, axis=1, sense=-1, material=wmat))
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(aabbEnlargeFactor=1.5), Bo1_Wall_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(interactionDetectionFactor=1.5),
                     Ig2_Wall_Sphere_ScGeom()],
                    [Ip2_JCFpmMat_JCFpmMat_JCFpmPhys(cohesiveTresholdIteration=1),
                     Ip2_FrictMat_FrictMat_FrictPhys()],
                    [Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM(),
                     Law2_ScGeom_FrictPhys_CundallStrack()]),
    NewtonIntegrator(damping=0.7),
]
O.dt = 0.5 * utils.PWaveTimeStep()
O.step()                                    # bonds form at the first iteration
for e in O.engines:                         # then detect only touching pairs
    if isinstance(e, InsertionSortCollider):
        e.boundDispatcher.functors[0].aabbEnlargeFactor = 1.0
    if isinstance(e, InteractionLoop):
        e.geomDispatcher.functors[0].interactionDetectionFactor = 1.0
v = 0.05
O.bodies[lo].state.vel = (0, v, 0)
O.bodies[hi].state.vel = (0, -v, 0)
O.run(200, True)
t0 = time.perf_counter()
O.run(1000, True)
t = time.perf_counter() - t0
n = len(ids)
print("YADE_RESULT " + json.dumps({"particles": n, "steps": 1000, "seconds": t,
      "particle_steps_per_s": n * 1000 / t, "dt": O.dt,
      "bonds": sum(1 for i in O.interactions if i.isReal and i.phys.isCohesive)}))
