"""PETSc CG + GAMG on a linear system written by `ribbar bench linear`.

Usage: python3 petsc-gamg.py DIR      (or --probe: print PETSc's version)

DIR holds system.json (sizes, tolerance), indptr.bin / indices.bin (int32)
and values.bin (float64): the scalar CSR of the whole symmetric matrix,
Dirichlet rows and columns already turned into identity ones; rhs.bin and
coords.bin (float64, x y z per node). Writes u.bin (float64) and
result.json (times, iterations, convergence). The near-null space is the
six rigid-body modes from the coordinates (MatNullSpaceCreateRigidBody),
block size 3: the standard PETSc set-up for elasticity.
"""

import glob
import json
import sys
import time

try:
    import petsc4py
except ImportError:
    # Debian installs petsc4py under PETSC_DIR, found through an
    # alternatives link that containers may lack.
    sys.path += sorted(glob.glob("/usr/lib/petscdir/*/*-real/lib/python3/dist-packages"))
    import petsc4py

petsc4py.init(sys.argv[:1])
from petsc4py import PETSc  # noqa: E402
import numpy as np  # noqa: E402


def main():
    if sys.argv[1:] == ["--probe"]:
        print(json.dumps({"version": ".".join(map(str, PETSc.Sys.getVersion()))}))
        return
    d = sys.argv[1]
    t0 = time.perf_counter()
    meta = json.load(open(f"{d}/system.json"))
    n = meta["rows"]
    indptr = np.fromfile(f"{d}/indptr.bin", dtype="<i4")
    indices = np.fromfile(f"{d}/indices.bin", dtype="<i4")
    values = np.fromfile(f"{d}/values.bin", dtype="<f8")
    rhs = np.fromfile(f"{d}/rhs.bin", dtype="<f8")
    coords = np.fromfile(f"{d}/coords.bin", dtype="<f8")
    a = PETSc.Mat().createAIJ(size=(n, n), bsize=3, csr=(indptr, indices, values))
    a.assemble()
    a.setOption(PETSc.Mat.Option.SPD, True)
    del indptr, indices, values
    xyz = PETSc.Vec().createWithArray(coords, bsize=3)
    a.setNearNullSpace(PETSc.NullSpace().createRigidBody(xyz))
    b = PETSc.Vec().createWithArray(rhs)
    x = b.duplicate()
    x.set(0.0)
    ksp = PETSc.KSP().create()
    ksp.setOperators(a)
    ksp.setType("cg")
    ksp.getPC().setType("gamg")
    ksp.setTolerances(rtol=meta["tolerance"], atol=0.0, max_it=1000)
    ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
    ksp.setFromOptions()
    t_load = time.perf_counter() - t0
    t1 = time.perf_counter()
    ksp.setUp()
    t_setup = time.perf_counter() - t1
    t2 = time.perf_counter()
    ksp.solve(b, x)
    t_solve = time.perf_counter() - t2
    x.getArray().astype("<f8").tofile(f"{d}/u.bin")
    r = b.duplicate()
    a.mult(x, r)
    r.aypx(-1.0, b)
    result = {
        "version": ".".join(map(str, PETSc.Sys.getVersion())),
        "iterations": ksp.getIterationNumber(),
        "converged": int(ksp.getConvergedReason()),
        "relative_residual": r.norm() / max(b.norm(), 1e-300),
        "t_load": t_load,
        "t_setup": t_setup,
        "t_solve": t_solve,
    }
    json.dump(result, open(f"{d}/result.json", "w"))


if __name__ == "__main__":
    main()
