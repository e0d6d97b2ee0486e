#!/usr/bin/python3
# # Plate wrapping a rigid cylinder: an independent dolfinx reference
#
# This script computes a finite element reference solution of the
# `plate-cylinder` scene of the `anm` project (DESIGN.md section 4, after
# section 2.2 of the source paper): a thin clamped strip is pushed up by three
# dead point forces at its free end and wraps a fixed rigid cylinder placed
# just above it.  It is written for the Debian packages of dolfinx 0.5.2
# (`python3-dolfinx`), gmsh (`python3-gmsh`) and h5py (`python3-h5py`), which
# `reference/dolfinx/install.sh` installs, and runs in serial with
# `/usr/bin/python3`:
#
#     /usr/bin/python3 reference/dolfinx/plate_cylinder.py --nx 160 --ny 4
#     /usr/bin/python3 reference/dolfinx/plate_cylinder.py --smoke
#
# The model deliberately differs from the project's shell element so that the
# two solutions are independent:
#
# * the strip is a **3D St Venant-Kirchhoff solid** meshed with quadratic
#   27-node hexahedra (one layer through the thickness);
# * the contact is a **node-to-cylinder regularized law** on the nodes of the
#   mid-surface (the `z = 0` layer of the quadratic mesh), added by hand to the
#   assembled residual and Jacobian;
# * the equilibrium path is followed by a **Newton method with adaptive load
#   stepping** in the load factor `lambda`, with a MUMPS LU solve.
#
# Units are N, m, Pa throughout.
#
# ## Problem data
#
# | quantity | value |
# | --- | --- |
# | strip | `0 <= x <= 2`, `-0.1 <= y <= 0.1`, `-0.0004 <= z <= 0.0004` |
# | material | `E = 200 GPa`, `nu = 0.3` |
# | support | every node of the face `x = 0` is fixed |
# | cylinder | radius `0.5`, axis along `y` through `(1, *, 0.5001)`, fixed |
# | loads | `F = 10 lambda` N along `+z` at `(2, -0.1, 0)`, `(2, 0, 0)`, `(2, 0.1, 0)` |
# | contact law | `R (R/K + h) = eta (delta - h)`, `K = 1e9 N/m`, `eta = 1e-6 N` per node |
#
# The lowest line of the cylinder is at `z = 1e-4`, so the initial gap of the
# mid-surface node under it is `delta = 1e-4` m.

# +
import argparse
import json
import os
import platform
import signal
import sys
import time

import numpy as np

import gmsh
import h5py
import ufl
from mpi4py import MPI
from petsc4py import PETSc

import dolfinx
import dolfinx.fem.petsc
from dolfinx import fem, mesh
from dolfinx.io import gmshio

LENGTH, WIDTH, THICK = 2.0, 0.2, 0.0008
E_YOUNG, NU = 200.0e9, 0.3
CYL_CENTER = np.array([1.0, 0.5001])  # (x, z) of the cylinder axis
CYL_RADIUS = 0.5
K_PEN, ETA = 1.0e9, 1.0e-6
LOAD_PER_POINT = 10.0  # N per unit lambda, three points
LOAD_POINTS = [(2.0, -0.1, 0.0), (2.0, 0.0, 0.0), (2.0, 0.1, 0.0)]
POINT_A = (2.0, 0.0, 0.0)
ROWS = {"B": 1.0, "C": 1.1, "D": 1.2}
TARGETS = [0.05, 0.1, 0.2, 0.5, 1.0]
# -

# ## Command line
#
# `--nx`, `--ny` are the numbers of quadratic elements along the length and the
# width (one element through the thickness).  The node rows at
# `x = 1.0, 1.1, 1.2` (points B, C, D) must exist, so `nx` must be a multiple of
# 20 (the element length `2/nx` divides 0.1).  `--smoke` runs a coarse mesh up
# to `lambda = 0.05` in well under two minutes and writes its files with the
# mesh name `smoke` (by default into a temporary directory).

# +
parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--nx", type=int, default=160, help="elements along x")
parser.add_argument("--ny", type=int, default=4, help="elements along y")
parser.add_argument("--lambda-max", type=float, default=1.0)
parser.add_argument("--out", default=None,
                    help="output folder (default reference/data/plate-cylinder)")
parser.add_argument("--name", default=None, help="mesh name used in file names")
parser.add_argument("--smoke", action="store_true",
                    help="coarse quick run (nx=40, ny=2, lambda-max=0.05)")
parser.add_argument("--candidate-gap", type=float, default=float("inf"),
                    help="nodes whose initial gap is below this are contact candidates [m]")
parser.add_argument("--rn-threshold", type=float, default=1e-3,
                    help="a node is 'in contact' when R exceeds this [N]")
parser.add_argument("--dlam0", type=float, default=1e-5, help="first load increment")
parser.add_argument("--dlam-max", type=float, default=0.02, help="largest load increment")
parser.add_argument("--max-steps", type=int, default=20000)
parser.add_argument("--nu", type=float, default=NU,
                    help="Poisson ratio (0.3; 0 is used for the beam check only)")
parser.add_argument("--check-only", action="store_true",
                    help="only run the linear cantilever check and exit")
parser.add_argument("--verbose", action="store_true", help="print every Newton iteration")
parser.add_argument("--time-newton", action="store_true",
                    help="only time a few Newton iterations and exit")
args = parser.parse_args()
NU = args.nu
VERBOSE = args.verbose
if args.smoke:
    args.nx, args.ny = 40, 2
    args.lambda_max = min(args.lambda_max, 0.05)
    if args.out is None:
        args.out = "/tmp/plate-cylinder-smoke"
name = args.name or ("smoke" if args.smoke else f"nx{args.nx}_ny{args.ny}")
here = os.path.dirname(os.path.abspath(__file__))
outdir = args.out or os.path.normpath(os.path.join(here, "..", "data", "plate-cylinder"))
os.makedirs(outdir, exist_ok=True)
if (args.nx * 0.1 / LENGTH) != round(args.nx * 0.1 / LENGTH):
    sys.exit("--nx must be a multiple of 20 so that node rows exist at x = 1.0, 1.1, 1.2")
if args.ny % 2:
    sys.exit("--ny must be even (a node line is needed at y = 0 and at y = +-0.1)")
comm = MPI.COMM_WORLD
assert comm.size == 1, "this script runs in serial"
t_start = time.perf_counter()
# -

# ## Mesh
#
# gmsh builds the box, makes every curve transfinite (`nx`, `ny`, 1 divisions
# along x, y, z), recombines the faces into quadrangles, meshes the volume as
# hexahedra and raises the order to 2.  gmsh's default second-order hexahedron
# is the complete 27-node one (`Mesh.SecondOrderIncomplete = 0`), which dolfinx
# reads as a degree-2 hexahedral geometry.  The quadratic nodes give three node
# layers through the thickness; the middle one (`z = 0`) is the mid-surface.
#
# Element shape matters here: one quadratic element through a 0.8 mm thickness
# is accurate in bending only if the elements are short along x (about
# `dx <= 0.0125` m); longer ones lock in membrane/shear.
#
# (Debian's dolfinx 0.5.2 `gmshio.read_from_msh` is broken, so the mesh is
# handed over in memory with `gmshio.model_to_mesh`.)

# +
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("strip")
gmsh.model.occ.addBox(0.0, -WIDTH / 2, -THICK / 2, LENGTH, WIDTH, THICK)
gmsh.model.occ.synchronize()
for dim, tag in gmsh.model.getEntities(1):
    x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(dim, tag)
    ext = np.array([x1 - x0, y1 - y0, z1 - z0])
    n = [args.nx, args.ny, 1][int(np.argmax(ext))]
    gmsh.model.mesh.setTransfiniteCurve(tag, n + 1)
for dim, tag in gmsh.model.getEntities(2):
    gmsh.model.mesh.setTransfiniteSurface(tag)
    gmsh.model.mesh.setRecombine(dim, tag)
for dim, tag in gmsh.model.getEntities(3):
    gmsh.model.mesh.setTransfiniteVolume(tag)
gmsh.model.addPhysicalGroup(3, [t for _, t in gmsh.model.getEntities(3)], 1)
gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
gmsh.model.mesh.generate(3)
gmsh.model.mesh.setOrder(2)
gmsh_version = gmsh.__version__
domain, _, _ = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=3)
gmsh.finalize()
ncells = domain.topology.index_map(3).size_local
cell_name = domain.topology.cell_type.name
print(f"mesh {name}: {ncells} {cell_name} cells, geometry nodes "
      f"{domain.geometry.x.shape[0]}", flush=True)
# -

# ## Function space, clamp, kinematics and material
#
# The displacement `u` lives in the vector Lagrange space of degree 2, whose
# nodes coincide with the 27-node hexahedra's nodes.  The Green-Lagrange strain
# is written `E = (G + G^T + G^T G)/2` with `G = grad u`, which is free of the
# cancellation of `(F^T F - I)/2` at small strains (this matters for the
# linear-cantilever check at tiny loads).  The second Piola-Kirchhoff stress is
# `S = lambda tr(E) I + 2 mu E` (3D law, no plane-stress condensation) and the
# internal virtual work is `int S : dE dX`, obtained as the derivative of the
# strain energy `W = S : E / 2`.  A 3x3x3 Gauss rule (quadrature degree 4) is
# the full integration of the quadratic hexahedron.

# +
V = fem.VectorFunctionSpace(domain, ("Lagrange", 2))
u = fem.Function(V, name="u")
v = ufl.TestFunction(V)
du = ufl.TrialFunction(V)

fdim = domain.topology.dim - 1
clamped_facets = mesh.locate_entities_boundary(domain, fdim, lambda x: np.isclose(x[0], 0.0))
clamped_dofs = fem.locate_dofs_topological(V, fdim, clamped_facets)
bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), clamped_dofs, V)

mu_l = E_YOUNG / (2 * (1 + NU))
lam_l = E_YOUNG * NU / ((1 + NU) * (1 - 2 * NU))
G = ufl.grad(u)
Egl = 0.5 * (G + G.T + G.T * G)
S = lam_l * ufl.tr(Egl) * ufl.Identity(3) + 2 * mu_l * Egl
dxq = ufl.Measure("dx", domain=domain, metadata={"quadrature_degree": 4})
energy = 0.5 * ufl.inner(S, Egl) * dxq
F_form = fem.form(ufl.derivative(energy, u, v))
J_form = fem.form(ufl.derivative(ufl.derivative(energy, u, v), u, du))
# -

# ## Nodes: mid-surface, loads, output rows
#
# `tabulate_dof_coordinates` gives one coordinate per node of the blocked vector
# space; in serial, node `i` owns the dofs `3 i`, `3 i + 1`, `3 i + 2`
# (x, y, z).  The mid-surface nodes are those at `z = 0`.

# +
Xn = V.tabulate_dof_coordinates()  # (n_nodes, 3) reference coordinates
n_nodes = V.dofmap.index_map.size_local
Xn = Xn[:n_nodes]
ndofs = 3 * n_nodes
tol = 1e-9
mid = np.flatnonzero(np.abs(Xn[:, 2]) < tol)


def node_at(p):
    d = np.linalg.norm(Xn - np.asarray(p), axis=1)
    i = int(np.argmin(d))
    assert d[i] < tol, f"no node at {p}"
    return i


load_nodes = [node_at(p) for p in LOAD_POINTS]
node_A = node_at(POINT_A)
print(f"{ndofs} dofs, {len(mid)} mid-surface nodes", flush=True)
# -

# ## Contact law
#
# Each mid-surface node is a contact node.  In the x-z plane let `c` be the
# cylinder axis and `x` the current node position; the signed distance to the
# cylinder surface is `h = |x - c| - r`, `delta` is its initial value and the
# outward normal of the cylinder at the node is `n = (x - c)/|x - c|`.  The
# regularized law `R (R/K + h) = eta (delta - h)` has the positive root
#
#     R(h) = (K/2) (-h + s),  s = sqrt(h^2 + 4 eta (delta - h)/K),
#
# computed as `R = 2 eta (delta - h)/(h + s)` when `h >= 0` to avoid
# cancellation.  Differentiating the law, `dR/dh = -(eta + R)/s`.  The cylinder
# pushes the node away from its axis: the nodal force is `f = R n` and its
# derivative with respect to the node position (x-z block) is
#
#     df/dx = dR/dh n n^T + R/|x - c| (I - n n^T).
#
# Because the law gives `R -> -eta` as the node moves away from the obstacle,
# every contact node far from the cylinder feels a pull of at most `eta`
# (1e-6 N).  The *candidate* nodes are the mid-surface nodes whose initial gap
# is below `--candidate-gap`.  The default keeps them all (the clamped row
# excepted): a cut on the initial gap such as 0.3 m would keep only
# `0.375 < x < 1.625`, but the free end of the strip wraps onto the cylinder
# beyond `x = 1.625` as lambda grows, so those nodes must stay candidates.  With
# a cut, the skipped nodes would change the total force by at most `eta` each
# (a few 1e-3 N for all of them, against loads of 30 lambda N).

# +
Xm = Xn[mid]
dist0 = np.hypot(Xm[:, 0] - CYL_CENTER[0], Xm[:, 2] - CYL_CENTER[1])
gap0 = dist0 - CYL_RADIUS
keep = (gap0 < args.candidate_gap) & (Xm[:, 0] > tol)  # the clamped row is fixed anyway
cand = mid[keep]
delta_c = gap0[keep]
Xc = Xn[cand]
dof_cx = 3 * cand
dof_cz = 3 * cand + 2
n_skipped = len(mid) - len(cand)
print(f"{len(cand)} contact candidates (initial gap < {args.candidate_gap} m), "
      f"{n_skipped} mid-surface nodes skipped", flush=True)


def contact_law(h, delta):
    """Positive root R(h) of R (R/K + h) = eta (delta - h), and dR/dh."""
    s = np.sqrt(h * h + 4.0 * ETA * (delta - h) / K_PEN)
    R = np.where(h >= 0.0,
                 2.0 * ETA * (delta - h) / np.maximum(h + s, 1e-300),
                 0.5 * K_PEN * (-h + s))
    dR = -(ETA + R) / s
    return R, dR


def contact_state(uarr):
    """Contact forces on the candidates for the displacement array `uarr`."""
    px = Xc[:, 0] + uarr[dof_cx] - CYL_CENTER[0]
    pz = Xc[:, 2] + uarr[dof_cz] - CYL_CENTER[1]
    dist = np.hypot(px, pz)
    h = dist - CYL_RADIUS
    R, dR = contact_law(h, delta_c)
    return R, dR, px / dist, pz / dist, dist
# -

# ## Residual and Jacobian
#
# The residual is `r(u, lambda) = f_int(u) - lambda f_ext - f_contact(u)`.
# `f_int` and its Jacobian are assembled by dolfinx; the three point loads
# (`10 lambda` N each along +z) and the nodal contact forces are added to the
# PETSc vector and matrix by dof index.  Clamped dofs get a zero residual and an
# identity row/column (dolfinx inserts the unit diagonal; the candidate nodes
# are far from the clamp, so the contact terms never touch a clamped dof).

# +
b = dolfinx.fem.petsc.create_vector(F_form)
A = dolfinx.fem.petsc.create_matrix(J_form)
dU = fem.Function(V)
bc_dofs = np.concatenate([3 * clamped_dofs + k for k in range(3)])
assert not np.intersect1d(cand, clamped_dofs).size
load_dofs_z = np.array([3 * i + 2 for i in load_nodes], dtype=np.int32)


def assemble_residual(lam):
    with b.localForm() as bl:
        bl.set(0.0)
    dolfinx.fem.petsc.assemble_vector(b, F_form)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    arr = b.getArray()  # writeable view in serial
    arr[load_dofs_z] -= LOAD_PER_POINT * lam
    R, dR, nx_, nz_, dist = contact_state(u.x.array)
    arr[dof_cx] -= R * nx_
    arr[dof_cz] -= R * nz_
    arr[bc_dofs] = 0.0
    return R


def assemble_jacobian():
    A.zeroEntries()
    dolfinx.fem.petsc.assemble_matrix(A, J_form, bcs=[bc])
    A.assemble()
    R, dR, nx_, nz_, dist = contact_state(u.x.array)
    # -(df/dx) in the (x, z) block of each candidate node
    t = R / dist
    kxx = -(dR * nx_ * nx_ + t * (1.0 - nx_ * nx_))
    kxz = -(dR * nx_ * nz_ - t * nx_ * nz_)
    kzz = -(dR * nz_ * nz_ + t * (1.0 - nz_ * nz_))
    for i in range(len(cand)):
        rows = [int(dof_cx[i]), int(dof_cz[i])]
        A.setValues(rows, rows, [kxx[i], kxz[i], kxz[i], kzz[i]],
                    addv=PETSc.InsertMode.ADD_VALUES)
    A.assemble()


ksp = PETSc.KSP().create(comm)
ksp.setType("preonly")
ksp.getPC().setType("lu")
ksp.getPC().setFactorSolverType("mumps")
ksp.setOperators(A)
# -

# ## Newton iterations at fixed lambda
#
# The residual norm is a poor convergence measure here: the through-thickness
# stiffness of a 0.8 mm solid layer is huge (`E/t`), so self-equilibrated
# thickness forces of tiny consequence dominate its norm.  Convergence is
# therefore declared on the correction: `max|du| <= 1e-8 max|u|` (plus an
# absolute floor of 1e-14 m).  Newton converges quadratically, so the error
# left after such a correction is far below it; the largest final residual
# norm is recorded in the metadata.  An
# iteration fails on a NaN, on a correction larger than 10 m, or after 25
# iterations; the load stepping then retries with a smaller increment.

# +
stats = {"newton_iterations": 0, "jacobians": 0, "failed_steps": 0}
t_jac = []
t_solve = []


def newton(lam, maxit=25):
    rnorm0 = None
    for it in range(1, maxit + 1):
        R = assemble_residual(lam)
        rnorm = b.norm()
        if not np.isfinite(rnorm):
            return False, it, rnorm
        if rnorm0 is None:
            rnorm0 = rnorm
        t0 = time.perf_counter()
        assemble_jacobian()
        t1 = time.perf_counter()
        b.scale(-1.0)
        ksp.solve(b, dU.vector)
        t2 = time.perf_counter()
        t_jac.append(t1 - t0)
        t_solve.append(t2 - t1)
        stats["jacobians"] += 1
        stats["newton_iterations"] += 1
        dmax = float(np.abs(dU.x.array).max())
        if not np.isfinite(dmax) or dmax > 10.0:
            return False, it, rnorm
        u.x.array[:] += dU.x.array
        umax = float(np.abs(u.x.array).max())
        if VERBOSE:
            print(f"    it {it}: |r| {rnorm:.3e} max|du| {dmax:.3e} max|u| {umax:.3e}", flush=True)
        if dmax <= 1e-8 * umax + 1e-14:
            assemble_residual(lam)
            rfin = b.norm()
            stats["max_final_residual"] = max(stats.get("max_final_residual", 0.0), rfin)
            return True, it, rfin
    return False, maxit, rnorm
# -

# ## Timing mode
#
# `--time-newton` measures the cost of one Newton iteration (Jacobian assembly
# and LU solve) on the chosen mesh and exits; use it to size the meshes.

# +
if args.time_newton:
    u.x.array[:] = 0.0
    for k in range(3):
        assemble_residual(1e-6)
        t0 = time.perf_counter()
        assemble_jacobian()
        t1 = time.perf_counter()
        ksp.solve(b, dU.vector)
        t2 = time.perf_counter()
        print(f"jacobian assembly {t1 - t0:.3f} s, MUMPS LU solve {t2 - t1:.3f} s", flush=True)
    print(f"setup (mesh, JIT, ...) {t0 - t_start:.1f} s")
    sys.exit(0)
# -

# ## Check 1: linear cantilever
#
# At a tiny load the strip is a linear cantilever: with contact switched off, a
# tip force `P = 30 lambda` N gives `uz_A = P L^3/(3 E I)`, `I = b t^3/12`.  We
# solve at `lambda = 1e-7` without contact (one Newton step is enough) and
# print the ratio.  The 3D solid is slightly stiffer than Euler-Bernoulli
# because the clamp also blocks the anticlastic (Poisson) curvature over a
# length of the order of the width near `x = 0`; `--check-only --nu 0` removes
# that effect and isolates the discretization error.

# +
I_beam = WIDTH * THICK**3 / 12
lam_check = 1e-7
cand_saved = (cand, delta_c, Xc, dof_cx, dof_cz)
cand, delta_c, Xc, dof_cx, dof_cz = (cand[:0], delta_c[:0], Xc[:0], dof_cx[:0], dof_cz[:0])
u.x.array[:] = 0.0
ok, its, _ = newton(lam_check)
uz_lin = u.x.array[3 * node_A + 2]
uz_theory = 3 * LOAD_PER_POINT * lam_check * LENGTH**3 / (3 * E_YOUNG * I_beam)
cantilever = {"lambda": lam_check, "uz_A_fe": float(uz_lin), "uz_A_beam": float(uz_theory),
              "ratio": float(uz_lin / uz_theory), "newton_iterations": its, "contact": "off",
              "nu": NU}
print(f"linear cantilever check (nu={NU:g}) at lambda={lam_check:g}: uz_A = {uz_lin:.6e} m, "
      f"P L^3/(3EI) = {uz_theory:.6e} m, ratio {uz_lin / uz_theory:.5f}", flush=True)
cand, delta_c, Xc, dof_cx, dof_cz = cand_saved
if args.check_only:
    sys.exit(0)
u.x.array[:] = 0.0
stats = {"newton_iterations": 0, "jacobians": 0, "failed_steps": 0}
# -

# ## Outputs
#
# At every converged load step we record the tip displacement at A, the sums of
# the nodal contact forces `R` over the node rows across the width at
# `x = 1.0, 1.1, 1.2` (B, C, D), the sum over all candidates, and the contact
# zone: the smallest and largest *initial* x of the nodes with
# `R > --rn-threshold` (1e-3 N; NaN when no node passes it).  The deformed
# mid-surface is stored at the target values of lambda.

# +
row_idx = {k: np.flatnonzero(np.abs(Xc[:, 0] - x) < tol) for k, x in ROWS.items()}
for k, idx in row_idx.items():
    assert len(idx) == 2 * args.ny + 1, f"row {k} has {len(idx)} nodes"

csv_path = os.path.join(outdir, f"curves_{name}.csv")
h5_path = os.path.join(outdir, f"midsurface_{name}.h5")
csv = open(csv_path, "w")
csv.write("lambda,uz_A,ux_A,rn_B,rn_C,rn_D,rn_total,x_lo,x_hi\n")
h5 = h5py.File(h5_path, "w")
h5.attrs["description"] = ("plate-cylinder reference (dolfinx 3D St Venant-Kirchhoff "
                           "solid, hex27): mid-surface (z = 0) nodes")
h5.attrs["units"] = "m (coordinates and displacements), N (contact forces)"
h5.attrs["mesh"] = name
mid_sorted = mid[np.lexsort((Xn[mid, 1], Xn[mid, 0]))]
cand_pos = {int(n): i for i, n in enumerate(cand)}
first_contact = None
table = {}


def record(lam):
    global first_contact
    uarr = u.x.array
    R, _, _, _, _ = contact_state(uarr)
    rn = {k: float(R[idx].sum()) for k, idx in row_idx.items()}
    on = R > args.rn_threshold
    x_lo = float(Xc[on, 0].min()) if on.any() else float("nan")
    x_hi = float(Xc[on, 0].max()) if on.any() else float("nan")
    uz, ux = float(uarr[3 * node_A + 2]), float(uarr[3 * node_A])
    rtot = float(R.sum())
    if first_contact is None and rtot > args.rn_threshold:
        first_contact = lam
    csv.write(f"{lam:.10g},{uz:.10e},{ux:.10e},{rn['B']:.10e},{rn['C']:.10e},"
              f"{rn['D']:.10e},{rtot:.10e},{x_lo:.6f},{x_hi:.6f}\n")
    csv.flush()
    row = {"uz_A": uz, "ux_A": ux, "rn_B": rn["B"], "rn_C": rn["C"], "rn_D": rn["D"],
           "rn_total": rtot, "x_lo": x_lo, "x_hi": x_hi}
    for t in TARGETS:
        if abs(lam - t) < 1e-12:
            table[f"{t:g}"] = row
            g = h5.create_group(f"lambda_{t:g}")
            g.attrs["lambda"] = t
            X = Xn[mid_sorted]
            U = np.stack([uarr[3 * mid_sorted + k] for k in range(3)], axis=1)
            Rm = np.array([R[cand_pos[int(n)]] if int(n) in cand_pos else 0.0
                           for n in mid_sorted])
            g.create_dataset("X", data=X).attrs["units"] = "m (reference coordinates)"
            g.create_dataset("u", data=U).attrs["units"] = "m (displacement)"
            g.create_dataset("R", data=Rm).attrs["units"] = "N (nodal normal contact force)"
            h5.flush()
    return row
# -

# ## Adaptive load stepping
#
# Starting from the flat strip, the path is strongly nonlinear almost at once
# (the linear tip deflection at `lambda = 1` would be 47 m), so the load
# increment starts small (`--dlam0`).  After a converged step the increment
# grows by 1.5 when Newton needed at most 7 iterations and shrinks by 0.7 when
# it needed more than 12 (the moving contact point costs several iterations
# whatever the increment, as it passes from one node row to the next); a
# failed step restores the last converged state and
# halves the increment.  Increments are clipped to land exactly on the target
# values 0.05, 0.1, 0.2, 0.5, 1.  The first guess of each step is the secant
# extrapolation of the last two converged states.

# +
# A SIGTERM or SIGINT stops the stepping after the current step; the files
# and the metadata are still written (with `"interrupted": true`).
interrupted = []
signal.signal(signal.SIGTERM, lambda *a: interrupted.append(True))
signal.signal(signal.SIGINT, lambda *a: interrupted.append(True))
lam = 0.0
dlam = args.dlam0
u_prev = u.x.array.copy()
u_old = None
dlam_prev = None
step = 0
record(0.0)
t_loop = time.perf_counter()
while lam < args.lambda_max - 1e-14 and step < args.max_steps and not interrupted:
    nxt = min([t for t in TARGETS + [args.lambda_max] if t > lam + 1e-14])
    dl = min(dlam, nxt - lam, args.dlam_max)
    if u_old is not None and dlam_prev:
        u.x.array[:] = u_prev + (dl / dlam_prev) * (u_prev - u_old)
    else:
        u.x.array[:] = u_prev
    ok, its, rn = newton(lam + dl)
    if not ok:
        stats["failed_steps"] += 1
        u.x.array[:] = u_prev
        dlam = 0.5 * dl
        print(f"  step failed at lambda={lam + dl:.6g} (dlam {dl:.3g}, {its} its, "
              f"|r| {rn:.2e}); dlam -> {dlam:.3g}", flush=True)
        if dlam < 1e-12:
            print("load increment too small: stopping", flush=True)
            break
        continue
    step += 1
    u_old, u_prev = u_prev, u.x.array.copy()
    dlam_prev = dl
    lam = lam + dl
    if abs(lam - nxt) < 1e-12:
        lam = nxt
    row = record(lam)
    if its <= 7:
        dlam = 1.5 * dl if dl >= 0.999 * dlam else dlam
    elif its > 12:
        dlam = 0.7 * dl
    if step % 20 == 0 or lam in TARGETS:
        print(f"step {step}: lambda={lam:.6g} its={its} uz_A={row['uz_A']:.5f} "
              f"ux_A={row['ux_A']:.5f} rn_total={row['rn_total']:.4g} "
              f"zone=[{row['x_lo']:.4f},{row['x_hi']:.4f}] "
              f"({time.perf_counter() - t_loop:.0f} s)", flush=True)
csv.close()
h5.attrs["lambdas"] = np.array(sorted(float(k) for k in table))
h5.close()
# -

# ## Metadata
#
# `meta_<name>.json` records the tool versions, the mesh, the command line,
# the run time, the step and iteration counts, the thresholds and the table
# at the target values of lambda.

# +
run_time = time.perf_counter() - t_start
meta = {
    "scene": "plate-cylinder",
    "model": "3D St Venant-Kirchhoff solid, Q2 Lagrange on 27-node hexahedra, full 3x3x3 "
             "Gauss integration; node-to-cylinder regularized contact on mid-surface nodes",
    "versions": {"dolfinx": dolfinx.__version__, "petsc4py": PETSc.Sys.getVersion(),
                 "petsc4py_module": __import__("petsc4py").__version__,
                 "gmsh": gmsh_version, "h5py": h5py.__version__, "numpy": np.__version__,
                 "python": platform.python_version()},
    "mesh": {"name": name, "element": f"{cell_name} 27-node (gmsh order 2), Lagrange degree 2",
             "elements_xyz": [args.nx, args.ny, 1], "cells": ncells,
             "element_size_xyz_m": [LENGTH / args.nx, WIDTH / args.ny, THICK],
             "nodes": n_nodes, "dofs": ndofs, "mid_surface_nodes": int(len(mid)),
             "contact_candidates": int(len(cand)), "skipped_mid_surface_nodes": int(n_skipped)},
    "parameters": {"E": E_YOUNG, "nu": NU, "length": LENGTH, "width": WIDTH, "thickness": THICK,
                   "cylinder_center_xz": CYL_CENTER.tolist(), "cylinder_radius": CYL_RADIUS,
                   "K": K_PEN, "eta": ETA, "load_per_point_per_lambda": LOAD_PER_POINT,
                   "candidate_gap_m": (args.candidate_gap if np.isfinite(args.candidate_gap)
                                       else "inf (all mid-surface nodes but the clamped row)"),
                   "contact_threshold_N": args.rn_threshold},
    "command": "/usr/bin/python3 " + " ".join(
        [os.path.relpath(os.path.abspath(sys.argv[0]), os.path.join(here, "..", ".."))]
        + sys.argv[1:]),
    "run_time_s": round(run_time, 1),
    "lambda_reached": lam,
    "interrupted": bool(interrupted),
    "load_steps": step,
    "failed_steps": stats["failed_steps"],
    "newton_iterations": stats["newton_iterations"],
    "mean_jacobian_assembly_s": float(np.mean(t_jac)) if t_jac else None,
    "mean_lu_solve_s": float(np.mean(t_solve)) if t_solve else None,
    "contact_start_lambda": first_contact,
    "linear_cantilever_check": cantilever,
    "targets": table,
}
with open(os.path.join(outdir, f"meta_{name}.json"), "w") as f:
    json.dump(meta, f, indent=2)
print(json.dumps({k: meta[k] for k in ("run_time_s", "lambda_reached", "load_steps",
                                       "newton_iterations", "contact_start_lambda")}))
for t, row in table.items():
    print(f"lambda={t}: uz_A={row['uz_A']:.6f} ux_A={row['ux_A']:.6f} "
          f"rn_total={row['rn_total']:.6f} zone=[{row['x_lo']:.4f}, {row['x_hi']:.4f}]")
# -
