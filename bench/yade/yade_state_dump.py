# Reads a Yade scene saved by poly_drop.py (POLY_DROP_SAVE=1) and writes, for
# bench/yade/bed_contacts.py, OUT/yade_contacts.csv (the interactions with a positive penetration
# volume: body ids, 0 = the wall; penetration volume, m^3; Yade's equivalent penetration depth and
# cross-section, m and m^2; normal force magnitude, N; the volumetric law gives a force only when
# the depth is > 0: a depth of 0 with a volume marks a pair whose bounding boxes overlap but whose
# bodies do not, see poly_drop.py state()) and OUT/yade_bodies.json (every body's
# vertices in the world frame, m, and its speed, m/s), so that the Yade bed can be measured with
# the same geometry code as kiln's.
# usage: HOME=<scratch> yade -j1 -n -x yade_state_dump.py STATE.xml.bz2 OUT
import json
import os
import sys

state, out = sys.argv[1], sys.argv[2]
O.load(state)
os.makedirs(out, exist_ok=True)
with open(os.path.join(out, "yade_contacts.csv"), "w") as f:
    f.write("id1,id2,penetration_volume,equivalent_depth,equivalent_cross_section,normal_force\n")
    for x in O.interactions:
        if x.isReal and x.geom.penetrationVolume > 0:
            f.write("%d,%d,%.9g,%.9g,%.9g,%.9g\n" % (
                x.id1, x.id2, x.geom.penetrationVolume, x.geom.equivalentPenetrationDepth,
                x.geom.equivalentCrossSection, x.phys.normalForce.norm()))
bodies = []
for b in O.bodies:
    if b.id == 0:
        continue  # the wall z = 0
    s = b.state
    bodies.append({"id": b.id, "speed": s.vel.norm(),
                   "vertices": [list(s.pos + s.ori * v) for v in b.shape.v]})
with open(os.path.join(out, "yade_bodies.json"), "w") as f:
    ke = sum(0.5 * b.state.mass * b.state.vel.squaredNorm()
             + 0.5 * sum(b.state.inertia[c] * (b.state.ori.conjugate() * b.state.angVel)[c] ** 2
                         for c in range(3)) for b in O.bodies if b.id != 0)
    json.dump({"time": O.time, "iter": O.iter, "kinetic_energy": ke, "bodies": bodies}, f)
print("DUMPED", O.time, len(bodies))
