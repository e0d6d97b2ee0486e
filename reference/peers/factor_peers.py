#!/usr/bin/env python3
"""Factor a sparse matrix (MatrixMarket) with the peers of anm's linear
solver: MKL Pardiso (through pypardiso's MKL) and MUMPS (python-mumps).

    python factor_peers.py MATRIX.mtx [--threads 1,2] [--json out.json]
                                      [--md out.md] [--repeat 3]
                                      [--solvers pardiso,mumps]
                                      [--kinds auto|spd,sym,general]
                                      [--mumps-ordering auto|amd|amf|scotch|pord|qamd]

Each (solver, kind, threads) runs in its own subprocess, started with
OMP_NUM_THREADS = MKL_NUM_THREADS = OPENBLAS_NUM_THREADS = threads, so that
its peak memory (getrusage ru_maxrss) is its own. A worker reads the matrix,
then times the analysis (ordering + symbolic factorization) once and the
numeric factorization `--repeat` times (the best is reported), solves once
for b = A·1 and reports the backward error |A x - b|_inf / (|A|_inf |x|_inf
+ |b|_inf), so that a fast but wrong factorization shows.

Kinds: `spd` (Pardiso mtype 2, MUMPS SYM=1: Cholesky), `sym` (Pardiso
mtype -2, MUMPS SYM=2: symmetric indefinite LDLᵀ), `general` (Pardiso
mtype 11, MUMPS SYM=0: LU). `auto`: spd and sym when the matrix is
symmetric (|A - Aᵀ|_max <= 1e-12 |A|_max), general otherwise. A kind that
does not apply (spd on an indefinite matrix) is reported as failed with the
solver's error, not hidden.

Output: a Markdown table on stdout (and in --md), every figure in --json:
per run solver, kind, ordering, threads requested and the threads the
libraries report (threadpoolctl), analysis time, numeric factorization time
(best and all), solve time, factor entries (Pardiso iparm(18), MUMPS
INFOG(29)), the solvers' own memory figures, peak RSS of the process and RSS
after reading the matrix (what the solver added is the difference).
"""

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time

KINDS = ("spd", "sym", "general")


def read_matrix(path, check_symmetry=True):
    import numpy as np
    import scipy.io
    import scipy.sparse as sp

    a = sp.csr_matrix(scipy.io.mmread(path))
    a.sum_duplicates()
    a.sort_indices()
    if a.shape[0] != a.shape[1]:
        raise SystemExit(f"{path}: not square: {a.shape}")
    if not check_symmetry:  # workers: no temporaries that would raise their peak RSS
        return a, None, None, np.ones(a.shape[0])
    amax = abs(a).max() if a.nnz else 0.0
    d = a - a.T
    asym = abs(d).max() if d.nnz else 0.0
    return a, float(amax), float(asym), np.ones(a.shape[0])


def maxrss_mib():
    # Linux: ru_maxrss in KiB.
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def thread_report():
    try:
        from threadpoolctl import threadpool_info

        def plain(v):
            return v if isinstance(v, (int, float, type(None))) else str(v)

        return [
            {"library": plain(i.get("internal_api")),
             "file": os.path.basename(str(i.get("filepath", ""))),
             "num_threads": plain(i.get("num_threads")), "version": plain(i.get("version"))}
            for i in threadpool_info()
        ]
    except Exception as e:  # noqa: BLE001 - informative only
        return [{"error": str(e)}]


def backward_error(a, x, b):
    import numpy as np

    r = a @ x - b
    na = abs(a).sum(axis=1).max()
    return float(np.abs(r).max() / (na * np.abs(x).max() + np.abs(b).max()))


def with_full_diagonal(u):
    """Pardiso's symmetric types need every diagonal entry stored."""
    import numpy as np
    import scipy.sparse as sp

    n = u.shape[0]
    have = np.zeros(n, dtype=bool)
    coo = u.tocoo()
    have[coo.row[coo.row == coo.col]] = True
    if have.all():
        return u
    miss = np.flatnonzero(~have)
    extra = sp.coo_matrix((np.zeros(len(miss)), (miss, miss)), shape=u.shape)
    out = (coo + extra).tocsr()  # adds explicit zeros, keeps them
    out.sort_indices()
    return out


def run_pardiso(a, kind, repeat, ones):
    import ctypes

    import numpy as np
    import pypardiso
    import scipy.sparse as sp

    solver = pypardiso.PyPardisoSolver()
    lib = solver.libmkl
    pardiso = solver._mkl_pardiso
    mtype = {"spd": 2, "sym": -2, "general": 11}[kind]
    m = with_full_diagonal(sp.triu(a, format="csr")) if kind != "general" else a
    m.sort_indices()
    n = m.shape[0]
    ia = m.indptr.astype(np.int32)
    ja = m.indices.astype(np.int32)
    data = np.ascontiguousarray(m.data, dtype=np.float64)
    pt = np.zeros(64, dtype=np.int64)
    iparm = np.zeros(64, dtype=np.int32)
    lib.pardisoinit.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_int32), ctypes.c_void_p]
    lib.pardisoinit(pt.ctypes.data, ctypes.byref(ctypes.c_int32(mtype)), iparm.ctypes.data)
    iparm[34] = 1  # zero-based ia, ja
    iparm[17] = -1  # report the nonzeros of the factors
    b = a @ ones
    x = np.zeros(n)
    err = ctypes.c_int32(0)
    i32p = ctypes.POINTER(ctypes.c_int32)
    f64p = ctypes.POINTER(ctypes.c_double)
    perm = np.zeros(n, dtype=np.int32)

    def call(phase):
        pardiso(pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
                ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(1)),
                ctypes.byref(ctypes.c_int32(mtype)), ctypes.byref(ctypes.c_int32(phase)),
                ctypes.byref(ctypes.c_int32(n)), data.ctypes.data_as(f64p),
                ia.ctypes.data_as(i32p), ja.ctypes.data_as(i32p), perm.ctypes.data_as(i32p),
                ctypes.byref(ctypes.c_int32(1)), iparm.ctypes.data_as(i32p),
                ctypes.byref(ctypes.c_int32(0)), b.ctypes.data_as(f64p), x.ctypes.data_as(f64p),
                ctypes.byref(err))
        if err.value != 0:
            why = {-1: "input inconsistent", -2: "not enough memory", -3: "reordering problem",
                   -4: "zero pivot (with mtype 2: not positive definite)", -7: "diagonal matrix is singular",
                   -8: "32-bit integer overflow"}.get(err.value, "see the MKL Pardiso manual")
            raise RuntimeError(f"Pardiso phase {phase}: error {err.value}: {why}")

    out = {"ordering": {0: "minimum degree", 2: "METIS", 3: "METIS (parallel)"}.get(int(iparm[1]), f"iparm(2) = {iparm[1]}")}
    try:
        t = time.perf_counter()
        call(11)
        out["analysis_s"] = time.perf_counter() - t
        times = []
        for _ in range(repeat):
            t = time.perf_counter()
            call(22)
            times.append(time.perf_counter() - t)
        out["factorization_s_all"] = times
        out["factorization_s"] = min(times)
        t = time.perf_counter()
        call(33)
        out["solve_s"] = time.perf_counter() - t
        out["backward_error"] = backward_error(a, x, b)
        out["factor_entries"] = int(iparm[17])
        out["perturbed_pivots"] = int(iparm[13])
        if kind == "sym":
            out["inertia"] = {"positive": int(iparm[21]), "negative": int(iparm[22])}
        out["solver_memory_MiB"] = {
            "analysis_peak": iparm[14] / 1024.0,
            "factorization_and_solve": (iparm[15] + iparm[16]) / 1024.0,
        }
        lib.MKL_Get_Max_Threads.restype = ctypes.c_int
        out["solver_threads"] = int(lib.MKL_Get_Max_Threads())
        vb = ctypes.create_string_buffer(256)
        lib.mkl_get_version_string(vb, 256)
        full = vb.value.decode().strip()
        out["version_full"] = full
        out["version"] = "MKL " + full.split("Version ")[-1].split("-")[0].split(" ")[0]
    finally:
        try:
            call(-1)
        except RuntimeError:
            pass
    return out


def run_mumps(a, kind, repeat, ones, ordering):
    import mumps
    import numpy as np
    import scipy.sparse as sp

    sym = {"spd": 1, "sym": 2, "general": 0}[kind]
    coo = (sp.triu(a) if sym else a).tocoo()
    ctx = mumps.Context()
    # The Context's set_matrix knows SYM = 0 and 2 only: make the instance here.
    from mumps import _mumps
    from mumps.mumps import _make_assembled_from_coo

    dtype, row, col, data = _make_assembled_from_coo(coo, False)
    inst = getattr(_mumps, dtype + "mumps")(False, sym)
    ctx.mumps_instance, ctx.dtype, ctx.n = inst, dtype, a.shape[0]
    ctx.row, ctx.col, ctx.data = row, col, data
    inst.set_assembled_matrix(a.shape[0], row, col, data)
    import glob

    libs = glob.glob(os.path.join(os.path.dirname(mumps.__file__), "..", "python_mumps.libs", "libdmumps_seq-*.so"))
    # libdmumps_seq-5-<hash>.2.1.so: MUMPS 5.2.1
    ver = ".".join([os.path.basename(libs[0]).split("-")[1]] + os.path.basename(libs[0]).split(".")[1:-1]) if libs else "?"
    out = {"version": f"MUMPS {ver} sequential", "binding": f"python-mumps {mumps.__version__}"}
    if ordering != "auto":
        inst.icntl[7] = mumps.orderings[ordering]
    inst.job = 1
    out["analysis_s"] = ctx.call()
    out["ordering"] = mumps.mumps.ordering_name[inst.infog[7]]
    est = inst.infog[20]
    out["factor_entries_estimate"] = est if est > 0 else -est * 1_000_000
    times = []
    for _ in range(repeat):
        inst.job = 2
        while True:
            try:
                t = ctx.call()
            except mumps.MUMPSError:
                if inst.infog[1] in (-8, -9):
                    inst.icntl[14] *= 2
                    continue
                raise
            break
        times.append(t)
    out["factorization_s_all"] = times
    out["factorization_s"] = min(times)
    ent = inst.infog[29]
    out["factor_entries"] = ent if ent > 0 else -ent * 1_000_000
    out["solver_memory_MiB"] = {"factorization": float(inst.infog[22])}
    if sym:
        out["negative_pivots"] = int(inst.infog[12])
    b = a @ ones
    ctx.factored = True
    t = time.perf_counter()
    x = np.asarray(ctx.solve(b)).reshape(-1)
    out["solve_s"] = time.perf_counter() - t
    out["backward_error"] = backward_error(a, x, b)
    out["solver_threads"] = None  # sequential MUMPS; BLAS threads below
    return out


def worker(args):
    t0 = time.perf_counter()
    a, _, _, ones = read_matrix(args.matrix, check_symmetry=False)
    rec = {
        "solver": args.worker[0],
        "kind": args.worker[1],
        "threads": int(args.worker[2]),
        "n": a.shape[0],
        "stored_entries": int(a.nnz),
        "read_s": time.perf_counter() - t0,
        "rss_after_read_MiB": maxrss_mib(),
    }
    try:
        if rec["solver"] == "pardiso":
            rec.update(run_pardiso(a, rec["kind"], args.repeat, ones))
        else:
            rec.update(run_mumps(a, rec["kind"], args.repeat, ones, args.mumps_ordering))
        rec["ok"] = True
    except Exception as e:  # noqa: BLE001 - reported in the table
        rec["ok"] = False
        rec["error"] = f"{type(e).__name__}: {e}".replace("\n", " ")
    rec["peak_rss_MiB"] = maxrss_mib()
    rec["thread_pools"] = thread_report()
    print("RESULT " + json.dumps(rec), flush=True)


def fmt(x, spec):
    return "–" if x is None else format(x, spec)


def negative(r):
    """Negative pivots (the inertia's negative count) where the solver gives it."""
    if "inertia" in r:
        return str(r["inertia"]["negative"])
    if "negative_pivots" in r:
        return str(r["negative_pivots"])
    return "–"


def markdown(matrix, info, recs):
    s = (f"`{matrix}`: n = {info['n']}, {info['stored_entries']} stored entries, "
         f"max |A - Aᵀ| / max |A| = {info['asymmetry']:.1e}; {info['cpus']} CPUs; "
         f"factorization: best of {info['repeat']}\n\n")
    s += ("| solver | kind | ordering | threads (requested / library) | analysis (s) | factorization (s) "
          "| solve (s) | backward error | factor entries | negative pivots | peak RSS (MiB) | RSS after reading (MiB) |\n")
    s += "|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    for r in recs:
        lib = r.get("solver_threads")
        if lib is None:
            # python-mumps' own OpenBLAS (libopenblasp-r0-*.so).
            blas = [p.get("num_threads") for p in r.get("thread_pools", [])
                    if "openblasp-r0" in str(p.get("file"))]
            lib = f"its OpenBLAS {blas[0]}" if blas else "–"
        if not r.get("ok"):
            s += (f"| {r['solver']} | {r['kind']} | {r.get('ordering', '–')} | {r['threads']} / {lib} "
                  f"| failed: {r.get('error', '?')} | | | | | | {fmt(r.get('peak_rss_MiB'), '.0f')} | "
                  f"{fmt(r.get('rss_after_read_MiB'), '.0f')} |\n")
            continue
        s += (f"| {r.get('version', r['solver'])} | {r['kind']} | {r.get('ordering', '–')} "
              f"| {r['threads']} / {lib} | {r['analysis_s']:.4f} | {r['factorization_s']:.4f} "
              f"| {r['solve_s']:.4f} | {r['backward_error']:.1e} | {r['factor_entries']:.3e} "
              f"| {negative(r)} | {r['peak_rss_MiB']:.0f} | {r['rss_after_read_MiB']:.0f} |\n")
    return s


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("matrix")
    p.add_argument("--threads", default="1,2", help="comma-separated thread counts (default 1,2)")
    p.add_argument("--json", help="write every figure here")
    p.add_argument("--md", help="write the Markdown table here")
    p.add_argument("--repeat", type=int, default=3, help="numeric factorizations per run (best reported)")
    p.add_argument("--solvers", default="pardiso,mumps")
    p.add_argument("--kinds", default="auto", help="auto, or a comma-separated subset of spd,sym,general")
    p.add_argument("--mumps-ordering", default="auto",
                   choices=["auto", "amd", "amf", "scotch", "pord", "qamd", "metis"])
    p.add_argument("--worker", nargs=3, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.worker:
        return worker(args)

    a, amax, asym, _ = read_matrix(args.matrix)
    rel = asym / amax if amax > 0 else 0.0
    if args.kinds == "auto":
        kinds = ["spd", "sym"] if rel <= 1e-12 else ["general"]
    else:
        kinds = args.kinds.split(",")
        bad = [k for k in kinds if k not in KINDS]
        if bad:
            raise SystemExit(f"--kinds: unknown {bad}; use {','.join(KINDS)}")
    info = {"matrix": args.matrix, "n": a.shape[0], "stored_entries": int(a.nnz), "asymmetry": rel,
            "cpus": os.cpu_count(), "repeat": args.repeat, "python": platform.python_version(),
            "OPENBLAS_CORETYPE": os.environ.get("OPENBLAS_CORETYPE")}
    del a
    recs = []
    for solver in args.solvers.split(","):
        for kind in kinds:
            for th in [int(t) for t in args.threads.split(",")]:
                env = dict(os.environ)
                for v in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
                    env[v] = str(th)
                env["MKL_DYNAMIC"] = "FALSE"
                cmd = [sys.executable, os.path.abspath(__file__), args.matrix, "--repeat", str(args.repeat),
                       "--mumps-ordering", args.mumps_ordering, "--worker", solver, kind, str(th)]
                pr = subprocess.run(cmd, env=env, capture_output=True, text=True)
                line = [x for x in pr.stdout.splitlines() if x.startswith("RESULT ")]
                if line:
                    rec = json.loads(line[-1][len("RESULT "):])
                else:
                    last = (pr.stderr.strip().splitlines() or ["no output"])[-1]
                    rec = {"solver": solver, "kind": kind, "threads": th, "ok": False,
                           "error": f"worker exit {pr.returncode}: {last}"}
                print(f"{solver} {kind} threads={th}: "
                      + (f"factorization {rec['factorization_s']:.4f} s, peak {rec['peak_rss_MiB']:.0f} MiB"
                         if rec.get("ok") else f"failed: {rec.get('error')}"), file=sys.stderr)
                recs.append(rec)
    md = markdown(args.matrix, info, recs)
    print(md, end="")
    if args.md:
        with open(args.md, "w") as f:
            f.write(md)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"matrix": info, "runs": recs}, f, indent=1)
    return 0 if all(r.get("ok") or r["kind"] == "spd" for r in recs) else 1


if __name__ == "__main__":
    sys.exit(main())
