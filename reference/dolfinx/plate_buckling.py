#!/usr/bin/python3
# # Simply supported square plate under uniaxial compression: an independent
# # dolfinx + SLEPc linear buckling reference
#
# This script computes the linear buckling load of the `plate-buckling`
# verification scene of the `anm` project (issue 14, requirement 5c;
# DESIGN.md section 8) with a model that shares nothing with the crate's
# shell element: the plate is a **3D linear elastic solid** meshed with
# quadratic 27-node hexahedra (Q2 Lagrange, `nz` layers through the
# thickness), the prebuckling stress comes from a linear solve, and the
# eigenproblem
#
#     (K + mu K_G(sigma_0)) phi = 0,   i.e.   K phi = mu (-K_G) phi      (1)
#
# is solved by SLEPc (Krylov-Schur, shift-and-invert about mu = 0 with a
# MUMPS LU of K).  K is the linear elastic stiffness, K_G the initial-stress
# (geometric) stiffness of the Green-Lagrange strain,
#
#     phi^T K_G psi = int_V sigma_0 : (grad phi^T grad psi) dV           (2)
#
# (e.g. Bathe, *Finite Element Procedures*, 2nd ed., section 6.8.2).  The
# data (E, nu, a, b, t, the edge line force per unit lambda) are read from
# `scenes/verification/plate-buckling.toml`, so `mu` is lambda_cr of that
# scene and `sigma_cr = mu N / t`.
#
# Written for the Debian bookworm packages (`python3-dolfinx` 0.5.2,
# `python3-slepc4py` 3.18), installed by `reference/dolfinx/install.sh`;
# serial, `/usr/bin/python3`:
#
#     /usr/bin/python3 reference/dolfinx/plate_buckling.py             # the reference
#
# writes `reference/data/plate-buckling/buckling.json` and `buckling.csv`.
#
# ## Boundary conditions: the shell's, on the 3D solid
#
# The shell scene: `uz = 0` on the four edges (director free: simply
# supported, rotation free), `ux = 0` on the edge x = 0, `uy = 0` at the
# corner (0, 0), the edges y = 0, b free in-plane, and a dead compressive
# line force N (per unit length, along -x) on the edge x = a.  The solid
# occupies `[0, a] x [0, b] x [-t/2, t/2]`; its mid-surface `z = 0` is the
# shell's reference surface (with nz odd or even the quadratic nodes include
# a node line on z = 0 along every edge).
#
# * Prebuckling supports on the **mid-surface lines only**: `uz = 0` on
#   the nodes with z = 0 of the four lateral faces, `ux = 0` on the nodes
#   with z = 0 of the face x = 0, `uy = 0` on the node (0, 0, 0).  Blocking
#   ux on a whole face would clamp the edge rotation (ux = -z w_x); with
#   the load below these supports carry no force and only remove the rigid
#   motions.
# * Supports of the buckling mode (`--supports`):
#   - `faces` (the reference): uz = 0 on the whole lateral faces, ux = 0
#     on the x = 0 mid-line, uy = 0 at (0, 0, 0).  The faces rotate freely
#     about the edge (ux = -z w_x on x = 0, a is free) and the edge may
#     twist (the tangential displacement is free): the **soft** simple
#     support, which is what the shell scene's free director gives (the
#     director may rotate about the edge normal too).  `lines`: uz = 0 on
#     the mid-lines only, as the prebuckling (a check; line constraints
#     are not well posed in 3D as h -> 0, they agree with `faces` to 1e-5
#     here).
#   - `hard`: in addition the tangential displacement of the lateral faces
#     (uy = 0 on x = 0, a; ux = 0 on y = 0, b): no edge twist, the
#     Navier/Kirchhoff condition that the closed form's mode
#     sin(pi x/a) sin(pi y/b) satisfies (w_y = 0 on x = 0, a).
#   The soft support carries a strong edge layer of width ~t and lowers
#   the buckling load by O(t/b) below the Kirchhoff value, the hard one by
#   O((t/b)^2) (Arnold & Falk, SIAM J. Math. Anal. 20 (1989) 282, "Edge
#   effects in the Reissner-Mindlin plate theory").  Uniform meshes much
#   coarser than t converge slowly to the soft value (0.2-0.7 % per halving
#   of h at t/b = 0.01), hence the edge grading `--grade` (element size
#   (1 - c) h at the edges).
# * Load as a **uniform traction N / t over the thickness** of the face
#   x = a (along -x), and the **equal and opposite traction on the face
#   x = 0**.  In the shell the support ux = 0 at x = 0 reacts exactly this
#   uniform line force; putting the reaction as a traction in the solid
#   makes the prebuckling state the homogeneous uniaxial stress
#   sigma_xx = -N/t (the linear Q2 solve reproduces it to round-off; the
#   script prints the deviation) and the line supports carry no load, so
#   no 3D stress concentration at a support line enters K_G.  The
#   constraint ux = 0 on the x = 0 mid-line still acts on the buckling mode
#   (1), as in the shell.  `--x0-load support` instead lets the mid-line
#   support react the load (a line reaction, as a shell node would): a
#   sensitivity check, not the reference.
# * The faces y = 0, b are traction free (Poisson expansion free), the
#   faces z = +-t/2 are traction free (plane stress through the thickness).
#
# The solid also carries what the shell omits or approximates (transverse
# shear, through-thickness strain): for t/b = 0.01 the Mindlin shear
# correction of the Kirchhoff value, 1 / (1 + D (alpha^2 + beta^2) /
# (kappa G t)) - 1 ~ -pi^2 t^2 (1/a^2 + 1/b^2) / (6 kappa (1 - nu)), is
# -5.6e-4 (kappa = 5/6, m = n = 1), below the comparison's 1%.
#
# ## Mesh convergence
#
# `--n` lists the in-plane divisions (n x n elements), `--nz` the layers.
# The stored file records every mesh and names the finest as the reference.

import argparse
import csv
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
from dolfinx import fem, mesh

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))

ap = argparse.ArgumentParser(description=__doc__)
ap.add_argument("--scene", default=os.path.join(ROOT, "scenes/verification/plate-buckling.toml"))
ap.add_argument("--n", type=int, nargs="+", default=[16, 32, 64],
                help="in-plane divisions (n x n quadratic hexahedra), one run each")
ap.add_argument("--nz", type=int, nargs="+", default=[2],
                help="layers through the thickness, one run per (n, nz)")
ap.add_argument("--modes", type=int, default=3)
ap.add_argument("--grade", type=float, default=0.8,
                help="edge grading c in [0, 1): edge elements (1 - c) times the mean size")
ap.add_argument("--supports", choices=["faces", "lines", "hard"], default="faces",
                help="uz = 0 of the mode on the whole lateral faces or on their mid-lines (header)")
ap.add_argument("--x0-load", choices=["traction", "support"], default="traction",
                help="how the load is reacted at x = 0 (see the header)")
ap.add_argument("--out", default=os.path.join(ROOT, "reference/data/plate-buckling"))
ap.add_argument("--name", default="buckling")
args = ap.parse_args()

# ## Scene data

with open(args.scene, "rb") as f:
    scene = tomllib.load(f)
E = float(scene["material"]["young"])
NU = float(scene["material"]["poisson"])
T = float(scene["shell"]["thickness"])
X0, X1 = scene["mesh"]["x"]
Y0, Y1 = scene["mesh"]["y"]
A, B = X1 - X0, Y1 - Y0
loads = [l for l in scene["load"] if l.get("edge") == "s1"]
assert len(loads) == 1, "expected one line force on edge s1"
N_LINE = -float(loads[0]["line_force"][0])  # compressive, N/m per unit lambda
assert N_LINE > 0.0
# Kirchhoff closed form (Timoshenko & Gere 1961, section 9.2), k = 4, a = b.
SIGMA_CLOSED = 4.0 * np.pi**2 * E / (12.0 * (1.0 - NU**2)) * (T / B) ** 2
LAME_MU = E / (2.0 * (1.0 + NU))
LAME_LAMBDA = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU))
print(f"scene {args.scene}: E={E} nu={NU} a={A} b={B} t={T} N={N_LINE} N/m per lambda")
print(f"closed form sigma_cr = {SIGMA_CLOSED:.6f} Pa (N/t = {N_LINE / T:.6f})")


def sigma(u):
    eps = ufl.sym(ufl.grad(u))
    return LAME_LAMBDA * ufl.tr(eps) * ufl.Identity(3) + 2.0 * LAME_MU * eps


def solve(n, nz):
    t0 = time.time()
    msh = mesh.create_box(MPI.COMM_WORLD,
                          [np.array([X0, Y0, -0.5 * T]), np.array([X1, Y1, 0.5 * T])],
                          [n, n, nz], mesh.CellType.hexahedron)
    if args.grade > 0.0:
        # Edge grading: xi -> xi - c sin(2 pi xi) / (2 pi) on [0, 1] in x
        # and y: element size (1 - c) h at the edges, (1 + c) h mid-span,
        # to resolve the edge layer of width ~t of the soft support.
        g = msh.geometry.x
        c = args.grade
        for k, (lo, length) in enumerate([(X0, A), (Y0, B)]):
            xi = (g[:, k] - lo) / length
            g[:, k] = lo + length * (xi - c * np.sin(2.0 * np.pi * xi) / (2.0 * np.pi))
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 2))
    tol = 1e-9 * max(A, B)

    def on_mid(x):
        return np.abs(x[2]) < 1e-6 * T

    def on_lateral(x):
        return ((np.abs(x[0] - X0) < tol) | (np.abs(x[0] - X1) < tol)
                | (np.abs(x[1] - Y0) < tol) | (np.abs(x[1] - Y1) < tol))

    markers = {
        "uz_lines": lambda x: on_mid(x) & on_lateral(x),
        "uz_faces": on_lateral,
        "ux": lambda x: on_mid(x) & (np.abs(x[0] - X0) < tol),
        "uy": lambda x: on_mid(x) & (np.abs(x[0] - X0) < tol) & (np.abs(x[1] - Y0) < tol),
    }
    # Hard support: the tangential displacement of the lateral faces too
    # (uy on x = X0, X1; ux on y = Y0, Y1): no rotation about the normal.
    markers["ux_tangential"] = lambda x: (np.abs(x[1] - Y0) < tol) | (np.abs(x[1] - Y1) < tol)
    markers["uy_tangential"] = lambda x: (np.abs(x[0] - X0) < tol) | (np.abs(x[0] - X1) < tol)
    counts, dirichlet = {}, {}
    for comp, name in [(0, "ux"), (1, "uy"), (2, "uz_lines"), (2, "uz_faces"),
                       (0, "ux_tangential"), (1, "uy_tangential")]:
        Vi, _ = V.sub(comp).collapse()
        dofs = fem.locate_dofs_geometrical((V.sub(comp), Vi), markers[name])
        counts[name] = int(len(dofs[0]))
        dirichlet[name] = fem.dirichletbc(PETSc.ScalarType(0.0), dofs[0], V.sub(comp))
    assert counts["uy"] == 1, counts
    # The mid-line node counts: 2n + 1 per edge with the quadratic nodes.
    assert counts["ux"] == 2 * n + 1, counts
    assert counts["uz_lines"] == 8 * n, counts
    # Prebuckling: mid-line supports only (they carry no load with the
    # traction on both faces: sigma_0 is the shell's homogeneous membrane
    # state). Mode: uz on the mid-lines or the whole lateral faces.
    bcs_pre = [dirichlet["ux"], dirichlet["uy"], dirichlet["uz_lines"]]
    if args.supports == "hard":
        bcs = [dirichlet["ux"], dirichlet["ux_tangential"], dirichlet["uy_tangential"],
               dirichlet["uz_faces"]]
    else:
        bcs = [dirichlet["ux"], dirichlet["uy"], dirichlet["uz_" + args.supports]]

    # Faces x = X0 (tag 1) and x = X1 (tag 2).
    fdim = msh.topology.dim - 1
    f0 = mesh.locate_entities_boundary(msh, fdim, lambda x: np.abs(x[0] - X0) < tol)
    f1 = mesh.locate_entities_boundary(msh, fdim, lambda x: np.abs(x[0] - X1) < tol)
    facets = np.concatenate([f0, f1]).astype(np.int32)
    tags = np.concatenate([np.full(len(f0), 1), np.full(len(f1), 2)]).astype(np.int32)
    order = np.argsort(facets)
    ft = mesh.meshtags(msh, fdim, facets[order], tags[order])
    ds = ufl.Measure("ds", domain=msh, subdomain_data=ft)

    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a_form = fem.form(ufl.inner(sigma(u), ufl.sym(ufl.grad(v))) * ufl.dx)
    trac = N_LINE / T  # Pa, uniform over the thickness
    L = ufl.inner(fem.Constant(msh, PETSc.ScalarType((-trac, 0.0, 0.0))), v) * ds(2)
    if args.x0_load == "traction":
        L += ufl.inner(fem.Constant(msh, PETSc.ScalarType((trac, 0.0, 0.0))), v) * ds(1)
    L_form = fem.form(L)

    K_pre = dolfinx.fem.petsc.assemble_matrix(a_form, bcs=bcs_pre, diagonal=1.0)
    K_pre.assemble()
    rhs = dolfinx.fem.petsc.assemble_vector(L_form)
    dolfinx.fem.petsc.apply_lifting(rhs, [a_form], [bcs_pre])
    rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(rhs, bcs_pre)

    ksp = PETSc.KSP().create(msh.comm)
    ksp.setOperators(K_pre)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    u0 = fem.Function(V)
    ksp.solve(rhs, u0.vector)
    u0.x.scatter_forward()

    # Prebuckling stress vs the homogeneous uniaxial state sigma_xx = -N/t.
    s_exact = ufl.as_matrix([[-trac, 0, 0], [0, 0, 0], [0, 0, 0]])
    dev = fem.assemble_scalar(fem.form(ufl.inner(sigma(u0) - s_exact, sigma(u0) - s_exact) * ufl.dx))
    ref = trac**2 * A * B * T
    stress_dev = float(np.sqrt(dev / ref))

    # (2): phi^T K_G psi = int sigma_0 : (grad phi^T grad psi).
    kg_form = fem.form(-ufl.inner(ufl.dot(ufl.grad(v), sigma(u0)), ufl.grad(u)) * ufl.dx)
    Bm = dolfinx.fem.petsc.assemble_matrix(kg_form, bcs=bcs, diagonal=0.0)
    Bm.assemble()
    K = dolfinx.fem.petsc.assemble_matrix(a_form, bcs=bcs, diagonal=1.0)
    K.assemble()

    eps = SLEPc.EPS().create(msh.comm)
    eps.setOperators(K, Bm)
    # -K_G is positive semidefinite here (compression along x): GHEP with
    # the B-semi-inner product (SLEPc purifies the eigenvectors).
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setDimensions(args.modes, PETSc.DECIDE, PETSc.DECIDE)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(0.0)
    eps.setTolerances(1e-12, 200)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(0.0)
    sksp = st.getKSP()
    sksp.setType("preonly")
    sksp.getPC().setType("lu")
    sksp.getPC().setFactorSolverType("mumps")
    eps.solve()
    nconv = eps.getConverged()

    # Mid-surface uz of each mode against sin(m pi x/a) sin(n pi y/b).
    Vz, zmap = V.sub(2).collapse()
    xz = Vz.tabulate_dof_coordinates()
    mid = np.abs(xz[:, 2]) < 1e-6 * T
    xs, ys = (xz[mid, 0] - X0) / A, (xz[mid, 1] - Y0) / B
    modes = []
    vr = K.createVecRight()
    for i in range(min(nconv, args.modes)):
        mu = eps.getEigenpair(i, vr).real
        err = eps.computeError(i, SLEPc.EPS.ErrorType.RELATIVE)
        w = vr.getArray()[np.asarray(zmap)][mid]
        best, score = None, 0.0
        for m in range(1, 5):
            for k in range(1, 5):
                s = np.sin(m * np.pi * xs) * np.sin(k * np.pi * ys)
                c = abs(np.dot(w, s)) / (np.linalg.norm(w) * np.linalg.norm(s))
                if c > score:
                    best, score = (m, k), c
        modes.append({"mu": float(mu), "sigma_cr_Pa": float(mu * trac),
                      "ratio_to_closed_form": float(mu * trac / SIGMA_CLOSED),
                      "relative_residual": float(err),
                      "half_waves_xy": list(best), "correlation": float(score)})
    ndofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    run = {"n": n, "nz": nz, "elements": [n, n, nz], "element": "hex27 Q2 Lagrange",
           "dofs": int(ndofs), "grade": args.grade, "constrained": counts, "x0_load": args.x0_load, "supports": args.supports,
           "prebuckling_stress_rel_deviation": stress_dev,
           "converged": int(nconv), "modes": modes, "wall_s": time.time() - t0}
    m1 = modes[0]
    print(f"[{args.supports} grade {args.grade}] n={n:3d} nz={nz} dofs={ndofs:7d}: mu1={m1['mu']:.8f} sigma_cr={m1['sigma_cr_Pa']:.4f} Pa "
          f"(/closed {m1['ratio_to_closed_form']:.6f}, mode {m1['half_waves_xy']}, res {m1['relative_residual']:.1e}), "
          + ", ".join(f"mu{j+1}={md['mu']:.6f} {md['half_waves_xy']}" for j, md in enumerate(modes[1:], 1))
          + f"; stress dev {stress_dev:.1e}; {run['wall_s']:.1f} s", flush=True)
    return run


runs = [solve(n, nz) for nz in args.nz for n in args.n]
finest = max(runs, key=lambda r: r["dofs"])
meta = {
    "case": "plate-buckling (issue 14 req. 5c): linear buckling of the simply supported "
            "square plate under uniaxial compression, 3D solid",
    "reference": {"n": finest["n"], "nz": finest["nz"], "mu": finest["modes"][0]["mu"],
                  "sigma_cr_Pa": finest["modes"][0]["sigma_cr_Pa"],
                  "note": "the finest mesh's first eigenvalue is the reference value"
                  if args.name == "buckling" else
                  "finest mesh of this series; the reference value of the comparison is buckling.json's"},
    "scene": os.path.relpath(args.scene, ROOT),
    "data": {"young": E, "poisson": NU, "a": A, "b": B, "thickness": T,
             "line_force_per_lambda": N_LINE, "sigma_closed_form_Pa": SIGMA_CLOSED},
    "model": {
        "solid": "3D linear elastic (Lame), [0,a]x[0,b]x[-t/2,t/2], Q2 27-node hexahedra, "
                 "dolfinx create_box",
        "eigenproblem": "K phi = mu (-K_G(sigma_0)) phi, K_G = int sigma_0 : grad(phi)^T grad(psi); "
                        "SLEPc Krylov-Schur GHEP, shift-and-invert at 0, MUMPS LU, tol 1e-12",
        "prebuckling_supports": "uz = 0 on the z = 0 node lines of the four lateral faces; ux = 0 on "
                                "the z = 0 node line of x = 0; uy = 0 at (0, 0, 0) (load free)",
        "mode_supports": {
            "hard": "uz = 0 on the four lateral faces, uy = 0 on x = 0 and x = a, ux = 0 on y = 0 and "
                    "y = b (whole faces), ux = 0 on the z = 0 line of x = 0",
            "faces": "uz = 0 on the four lateral faces (soft), ux = 0 on the z = 0 line of x = 0, "
                     "uy = 0 at (0, 0, 0)",
            "lines": "as the prebuckling supports (soft)"}[args.supports],
        "load": "uniform traction N/t along -x on the face x = a over the thickness; "
                + ("equal and opposite traction on x = 0 (the shell support's reaction)"
                   if args.x0_load == "traction" else "reacted by the x = 0 mid-line support"),
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
with open(os.path.join(args.out, args.name + ".csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["n", "nz", "dofs", "mode", "mu", "sigma_cr_Pa", "ratio_to_closed_form",
                "half_waves_x", "half_waves_y", "relative_residual"])
    for r in runs:
        for j, md in enumerate(r["modes"], 1):
            w.writerow([r["n"], r["nz"], r["dofs"], j, f"{md['mu']:.10f}", f"{md['sigma_cr_Pa']:.6f}",
                        f"{md['ratio_to_closed_form']:.8f}", md["half_waves_xy"][0],
                        md["half_waves_xy"][1], f"{md['relative_residual']:.2e}"])
print("reference (finest):", meta["reference"])
