#!/usr/bin/env python3
"""Writes a test matrix for factor_peers.py: the 5-point Laplacian on an
m × m grid (Dirichlet boundary, n = m² unknowns, symmetric positive
definite), as a symmetric MatrixMarket file.

    python make_test_matrix.py OUT.mtx [--m 100] [--shift S]

--shift S subtracts S times the identity (S > 8 sin²(π/(2(m+1))), the
smallest eigenvalue, makes it indefinite: a stand-in for a tangent past a
bifurcation).
"""
import argparse

import scipy.io
import scipy.sparse as sp

p = argparse.ArgumentParser()
p.add_argument("out")
p.add_argument("--m", type=int, default=100)
p.add_argument("--shift", type=float, default=0.0)
a = p.parse_args()
t = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(a.m, a.m))
i = sp.identity(a.m)
lap = (sp.kron(t, i) + sp.kron(i, t) - a.shift * sp.identity(a.m * a.m)).tocoo()
scipy.io.mmwrite(a.out, lap, symmetry="symmetric",
                 comment=f"5-point Laplacian, {a.m} x {a.m} grid, shift {a.shift}")
print(f"{a.out}: n = {a.m * a.m}, {lap.nnz} entries")
