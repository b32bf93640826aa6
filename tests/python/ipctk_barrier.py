"""Reference values of the barrier contact from the IPC toolkit's Python bindings (ipctk).

Called by tests/barrier_ipctk.rs: python3 ipctk_barrier.py IN.json OUT.json
IN: {"vertices": [[x, y]...], "edges": [[i, j]...], "body": [b...] (per vertex),
     "vertices_t1": [[x, y]...], "dhat": d, "kappa": k}
OUT: {"energy": E, "gradient": [...], "step": t, "pairs": n (the collisions' weights summed:
      edge-vertex pairs, vertex-vertex collisions counted by their weights, the improved max
      approximator's negative vertex-vertex weights included), "version": "..."}
Vertices of different bodies interact only (a vertex and an edge of one body never do).
The collision set is the improved max approximator's (Li, Kaufman and Jiang 2023), without
area weighting: mpfem's barrier counts a node facing a vertex once (src/contact/barrier_problem.rs).
ipctk logs a warning that this set is meant for area weighting; the energy it computes is
the sum over the set all the same.
"""
import json
import sys

import numpy as np
import ipctk


def main(src, dst):
    # One thread: `can_collide` below is a Python function, and ipctk's broad phase calls it
    # from its worker threads. With several threads the workers wait for the interpreter's
    # lock while the main thread holds it inside ipctk, and the process hangs (seen in a
    # fresh-clone CI run: three threads waiting on futexes for minutes).
    ipctk.set_num_threads(1)
    with open(src) as f:
        case = json.load(f)
    V = np.asfortranarray(np.array(case["vertices"], dtype=float))
    V1 = np.asfortranarray(np.array(case["vertices_t1"], dtype=float))
    E = np.asfortranarray(np.array(case["edges"], dtype=np.int32))
    body = case["body"]
    mesh = ipctk.CollisionMesh(V, E)
    mesh.can_collide = lambda i, j: body[i] != body[j]
    collisions = ipctk.NormalCollisions()
    collisions.collision_set_type = ipctk.NormalCollisions.CollisionSetType.IMPROVED_MAX_APPROX
    collisions.build(mesh, V, case["dhat"])
    barrier = ipctk.BarrierPotential(case["dhat"], case["kappa"])
    energy = barrier(collisions, mesh, V)
    gradient = barrier.gradient(collisions, mesh, V)
    step = ipctk.compute_collision_free_stepsize(mesh, V, V1)
    pairs = sum(collisions[i].weight for i in range(len(collisions)))
    out = {
        "energy": float(energy),
        "gradient": [float(g) for g in gradient],
        "step": float(step),
        "pairs": float(pairs),
        "version": ipctk.__version__,
        "conservative_rescaling": ipctk.TightInclusionCCD.DEFAULT_CONSERVATIVE_RESCALING,
    }
    with open(dst, "w") as f:
        json.dump(out, f)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
