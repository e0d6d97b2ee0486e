#!/usr/bin/python3
# # Wrinkling of a stretched sheet clamped at both short ends: a dolfinx +
# # SLEPc linearized buckling reference (issue 14 item 6a)
#
# The `sheet-wrinkling` scene of the `anm` project (scenes/sheet-wrinkling.toml,
# whose E, nu, L, W, t and end displacement per unit lambda this script
# reads) as a **3D St Venant-Kirchhoff solid** of quadratic 27-node
# hexahedra (Q2 Lagrange, `nz` layers through the thickness): a model that
# shares nothing with the crate's shell element.
#
# Linearized buckling about the state at lambda_0, as `anm buckle --lambda
# lambda_0` (src/study/buckle.rs, (B1)-(B2)):
#
#     (K_0 + mu K_sigma) phi = 0,   lambda_cr = lambda_0 + mu,          (1)
#
#     K_0 = Kt(u_0),  K_sigma = d/dlambda Kt(u_0 + (lambda - lambda_0) u_t),
#     K_0 u_t = 0 with u_t = the end displacement per unit lambda on x = L,
#
# u_0 the equilibrium at lambda_0 (Newton, load steps of lambda_0 / steps),
# Kt the tangent of the SVK energy (the Green-Lagrange strain
# E = (F^T F - I) / 2, S = lambda_L tr(E) I + 2 mu_L E). UFL differentiates
# the energy twice for Kt and Kt once more along u_t for K_sigma (exact:
# Kt is quadratic in u). The eigenproblem K_0 phi = mu (-K_sigma) phi is
# solved by SLEPc (Krylov-Schur, GNHEP: -K_sigma is indefinite, tension
# along x and compression across; shift-and-invert about 0 with a MUMPS LU
# of K_0), the eigenvalues of smallest modulus.
#
# Boundary conditions: the whole face x = 0 clamped (u = 0); the whole face
# x = L held at u = (lambda * dx, 0, 0) (the shell's clamp of the
# mid-surface and of the director: no rotation, no contraction of the end).
#
#     /usr/bin/python3 reference/dolfinx/sheet_wrinkling.py --quarter --lambda0 3 --n 20 40 60 80 --steps 2
#     /usr/bin/python3 reference/dolfinx/sheet_wrinkling.py --quarter --lambda0 3 --n 100 --steps 2 --name wrinkling_n100
#
# writes reference/data/sheet-wrinkling/<name>.json (every mesh; the modes'
# mu, their number of wrinkles across the width and where they sit).

import argparse
import json
import os
import platform
import sys
import time
import tomllib

import numpy as np

import ufl
from mpi4py import MPI
from petsc4py import PETSc
from slepc4py import SLEPc

import dolfinx
import dolfinx.fem.petsc
import dolfinx.nls.petsc
from dolfinx import fem, mesh

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))

ap = argparse.ArgumentParser(description=__doc__)
ap.add_argument("--scene", default=os.path.join(ROOT, "scenes/sheet-wrinkling.toml"))
ap.add_argument("--lambda0", type=float, nargs="+", required=True,
                help="base states lambda_0 (one run per lambda_0 and mesh)")
ap.add_argument("--n", type=int, nargs="+", default=[40],
                help="divisions across the width; along the length n * L / W")
ap.add_argument("--nz", type=int, default=1, help="layers through the thickness")
ap.add_argument("--steps", type=int, default=4, help="Newton load steps to lambda_0")
ap.add_argument("--modes", type=int, default=4)
ap.add_argument("--quarter", action="store_true",
                help="the quarter x >= L/2, y >= 0 with symmetry planes (modes even in x and in y)")
ap.add_argument("--out", default=os.path.join(ROOT, "reference/data/sheet-wrinkling"))
ap.add_argument("--name", default="wrinkling")
args = ap.parse_args()

# ## Scene data

with open(args.scene, "rb") as f:
    scene = tomllib.load(f)
E = float(scene["material"]["young"])
NU = float(scene["material"]["poisson"])
T = float(scene["shell"]["thickness"])
X0, X1 = scene["mesh"]["x"]
Y0, Y1 = scene["mesh"]["y"]
LEN, WID = X1 - X0, Y1 - Y0
ends = [f for f in scene["fix"] if f.get("group") == "s1"]
assert len(ends) == 1 and ends[0]["dofs"][0] == "ux", "expected the s1 fix with ux first"
DX = float(ends[0]["value"][0])  # end displacement per unit lambda
assert all(v == 0.0 for v in ends[0]["value"][1:])
LAME_MU = E / (2.0 * (1.0 + NU))
LAME_LAMBDA = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU))
print(f"scene {args.scene}: E={E} nu={NU} L={LEN} W={WID} t={T} end ux = lambda * {DX}", flush=True)


def wrinkles(xyz, w):
    """Wrinkles of a mode's mid-surface uz = w: across the width on the
    node line x = const through |w|max (the number of crests, i.e. sign
    changes + 1, ignoring |w| < 1e-3 max), and the extent in x where
    |w| > max / 2 on the line y = const through |w|max."""
    i = int(np.argmax(np.abs(w)))
    big = abs(w[i])
    hx = 1e-9 * LEN
    across = np.abs(xyz[:, 0] - xyz[i, 0]) < hx
    ys = np.argsort(xyz[across, 1])
    line = w[across][ys]
    signs = np.sign(line[np.abs(line) > 1e-3 * big])
    crests = int(np.count_nonzero(signs[1:] != signs[:-1])) + 1
    along = np.abs(xyz[:, 1] - xyz[i, 1]) < 1e-9 * WID
    xs = xyz[along, 0][np.abs(w[along]) > 0.5 * big]
    return {"wrinkles": crests, "x_max": float(xyz[i, 0]), "y_max": float(xyz[i, 1]),
            "extent_x": [float(xs.min()), float(xs.max())]}


def solve(n, lambda0):
    t0 = time.time()
    nx = int(round(n * LEN / WID))
    lo, hi, size = np.array([X0, Y0, -0.5 * T]), np.array([X1, Y1, 0.5 * T]), [nx, n, args.nz]
    XM, YM = 0.5 * (X0 + X1), 0.5 * (Y0 + Y1)
    if args.quarter:
        # ## Quarter model (--quarter)
        # The state is even in y about y = W/2 and odd in x about x = L/2
        # (ux - lambda dx / 2 odd); the wrinkle modes come in near-double
        # pairs, uz even or odd in y, and are even in x. The quarter
        # x >= L/2, y >= 0 with ux = lambda dx / 2 on x = L/2 (mode: ux = 0
        # there) and uy = 0 on y = 0 gives the modes even in both: the
        # first of each pair whose uz is even in y. Same mesh density as
        # the full model's n, 4x fewer unknowns.
        lo = np.array([XM, YM, -0.5 * T])
        size = [nx // 2, n // 2, args.nz]
    msh = mesh.create_box(MPI.COMM_WORLD, [lo, hi], size, mesh.CellType.hexahedron)
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 2))
    tol = 1e-9 * LEN
    zero = fem.Function(V)
    u_end = fem.Function(V)
    right = fem.locate_dofs_geometrical(V, lambda x: np.abs(x[0] - X1) < tol)
    if args.quarter:
        Vx, _ = V.sub(0).collapse()
        Vy, _ = V.sub(1).collapse()
        mid_x = fem.locate_dofs_geometrical((V.sub(0), Vx), lambda x: np.abs(x[0] - XM) < tol)
        mid_y = fem.locate_dofs_geometrical((V.sub(1), Vy), lambda x: np.abs(x[1] - YM) < tol)
        half = fem.Constant(msh, PETSc.ScalarType(0.0))
        bc_y = fem.dirichletbc(PETSc.ScalarType(0.0), mid_y[0], V.sub(1))
        bcs = [fem.dirichletbc(u_end, right), fem.dirichletbc(half, mid_x[0], V.sub(0)), bc_y]
        bcs_mode = [fem.dirichletbc(zero, right),
                    fem.dirichletbc(PETSc.ScalarType(0.0), mid_x[0], V.sub(0)), bc_y]
    else:
        left = fem.locate_dofs_geometrical(V, lambda x: np.abs(x[0] - X0) < tol)
        bcs = [fem.dirichletbc(zero, left), fem.dirichletbc(u_end, right)]
        bcs_mode = [fem.dirichletbc(zero, left), fem.dirichletbc(zero, right)]

    def set_end(lam):
        u_end.interpolate(lambda x: np.vstack([np.full(x.shape[1], lam * DX),
                                               np.zeros(x.shape[1]), np.zeros(x.shape[1])]))
        if args.quarter:
            half.value = 0.5 * lam * DX

    # SVK energy, its residual and tangent.
    u = fem.Function(V)
    v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
    F = ufl.Identity(3) + ufl.grad(u)
    Egl = 0.5 * (F.T * F - ufl.Identity(3))
    psi = 0.5 * LAME_LAMBDA * ufl.tr(Egl) ** 2 + LAME_MU * ufl.inner(Egl, Egl)
    # 3 x 3 x 3 Gauss points (full integration of the Q2 stiffness).
    dx = ufl.dx(metadata={"quadrature_degree": 4})
    R = ufl.derivative(psi * dx, u, v)
    Kt = ufl.derivative(R, u, du)

    # ## Prebuckling: Newton to lambda_0 in load steps.
    newton_its = []
    if lambda0 != 0.0:
        problem = dolfinx.fem.petsc.NonlinearProblem(R, u, bcs, J=Kt)
        solver = dolfinx.nls.petsc.NewtonSolver(msh.comm, problem)
        # Converged when the Newton correction is below 1e-10 of the state.
        solver.rtol, solver.atol, solver.max_it = 1e-10, 0.0, 30
        solver.convergence_criterion = "incremental"
        ksp = solver.krylov_solver
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        for k in range(1, args.steps + 1):
            set_end(lambda0 * k / args.steps)
            its, ok = solver.solve(u)
            assert ok, f"Newton failed at lambda = {lambda0 * k / args.steps}"
            newton_its.append(int(its))
        u.x.scatter_forward()

    # ## u_t: K_0 u_t = 0, u_t = (DX, 0, 0) on x = L.
    set_end(1.0)
    zero_rhs = fem.form(ufl.inner(fem.Constant(msh, PETSc.ScalarType((0.0, 0.0, 0.0))), v) * ufl.dx)
    K0_form = fem.form(Kt)
    K_pre = dolfinx.fem.petsc.assemble_matrix(K0_form, bcs=bcs)
    K_pre.assemble()
    b = dolfinx.fem.petsc.assemble_vector(zero_rhs)
    dolfinx.fem.petsc.apply_lifting(b, [K0_form], [bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, bcs)
    ksp = PETSc.KSP().create(msh.comm)
    ksp.setOperators(K_pre)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ut = fem.Function(V)
    ksp.solve(b, ut.vector)
    ut.x.scatter_forward()

    # ## (1): K_0 and K_sigma with the mode's supports (both faces held).
    Ks_form = fem.form(ufl.derivative(Kt, u, ut))
    K = dolfinx.fem.petsc.assemble_matrix(K0_form, bcs=bcs_mode, diagonal=1.0)
    K.assemble()
    Bm = dolfinx.fem.petsc.assemble_matrix(Ks_form, bcs=bcs_mode, diagonal=0.0)
    Bm.assemble()
    Bm.scale(-1.0)

    eps = SLEPc.EPS().create(msh.comm)
    eps.setOperators(K, Bm)
    eps.setProblemType(SLEPc.EPS.ProblemType.GNHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setDimensions(args.modes, PETSc.DECIDE, PETSc.DECIDE)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(0.0)
    eps.setTolerances(1e-12, 500)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(0.0)
    sksp = st.getKSP()
    sksp.setType("preonly")
    sksp.getPC().setType("lu")
    sksp.getPC().setFactorSolverType("mumps")
    eps.solve()
    nconv = eps.getConverged()

    Vz, zmap = V.sub(2).collapse()
    xz = Vz.tabulate_dof_coordinates()
    # Q2 nodes include the plane z = 0 for any number of layers.
    mid = np.abs(xz[:, 2]) < 1e-6 * T
    modes = []
    vr = K.createVecRight()
    vi = K.createVecRight()
    for i in range(min(nconv, args.modes)):
        mu = eps.getEigenpair(i, vr, vi)
        err = eps.computeError(i, SLEPc.EPS.ErrorType.RELATIVE)
        w = vr.getArray()[np.asarray(zmap)][mid]
        md = {"mu": float(mu.real), "mu_imag": float(mu.imag),
              "lambda_critical": float(lambda0 + mu.real), "relative_residual": float(err)}
        xyz = xz[mid]
        if args.quarter:
            # The even mode on the whole sheet: mirror in y, then in x.
            XM, YM = 0.5 * (X0 + X1), 0.5 * (Y0 + Y1)
            for k, c in [(1, YM), (0, XM)]:
                m = xyz.copy()
                m[:, k] = 2.0 * c - m[:, k]
                xyz, w = np.vstack([xyz, m]), np.concatenate([w, w])
        md.update(wrinkles(xyz, w))
        modes.append(md)
    modes.sort(key=lambda m: abs(m["mu"]))
    ndofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    run = {"lambda0": lambda0, "n": n, "nx": nx, "nz": args.nz, "elements": size,
           "model": "quarter" if args.quarter else "full",
           "element": "hex27 Q2 Lagrange", "dofs": int(ndofs), "newton_iterations": newton_its,
           "converged": int(nconv), "modes": modes, "wall_s": time.time() - t0}
    print(f"lambda0={lambda0} n={n} {run['model']} ({size}) dofs={ndofs}: "
          + ", ".join(f"mu={m['mu']:.6f} (lambda_cr {m['lambda_critical']:.6f}, {m['wrinkles']} wrinkles, "
                      f"x {m['extent_x'][0]:.3f}-{m['extent_x'][1]:.3f}, res {m['relative_residual']:.1e})"
                      for m in modes)
          + f"; {run['wall_s']:.1f} s", flush=True)
    return run


runs = [solve(n, l0) for l0 in args.lambda0 for n in args.n]
meta = {
    "case": "sheet-wrinkling (issue 14 item 6a): linearized buckling of a stretched sheet "
            "clamped at both short ends, about the state at lambda_0, 3D SVK solid",
    "scene": os.path.relpath(args.scene, ROOT),
    "data": {"young": E, "poisson": NU, "length": LEN, "width": WID, "thickness": T,
             "end_displacement_per_lambda": DX},
    "model": {
        "solid": "3D St Venant-Kirchhoff, [0,L]x[-W/2,W/2]x[-t/2,t/2], Q2 27-node hexahedra, create_box",
        "prebuckling": f"Newton (MUMPS LU) to lambda_0 in {args.steps} load steps, corrections below 1e-10 relative",
        "eigenproblem": "Kt(u0) phi = mu (-dKt/dlambda along u_t) phi, UFL derivatives; SLEPc "
                        "Krylov-Schur GNHEP, shift-and-invert at 0, MUMPS LU, tol 1e-12",
        "supports": "face x = 0 clamped; face x = L at (lambda dx, 0, 0); modes: both faces held",
    },
    "runs": runs,
    "versions": {"dolfinx": dolfinx.__version__, "petsc4py": PETSc.Sys.getVersion(),
                 "slepc4py": SLEPc.Sys.getVersion(), "numpy": np.__version__,
                 "python": platform.python_version()},
    "command": " ".join([os.path.relpath(sys.argv[0], ROOT)] + sys.argv[1:]),
    "date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
}
os.makedirs(args.out, exist_ok=True)
with open(os.path.join(args.out, args.name + ".json"), "w") as f:
    json.dump(meta, f, indent=1)
