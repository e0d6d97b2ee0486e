"""False singular points of the geometric-series test in time (README,
"False singular points"): friction-plane and friction-roller over
zeta x omega x order x eps, each run by `anm run` and compared with IDA at
rtol = atol = 1e-10 (`anm reference ida`, needs --features reference).

    python3 reference/singular_sweep.py ./target/release/anm OUT_DIR

Prints one line per run (case, zeta, omega, order, eps, stop, stop time,
steps, factorizations, max relative error of u_x, u_y against IDA on the
output grid, the roller up to t = 2.25 s) and a summary: how many plane runs
reach the end (IDA does, at every cell) and how many roller runs stop before
t = 2.2 s (its breakdown is at ~2.30 s).
"""
import csv
import json
import os
import re
import subprocess
import sys

anm, out = sys.argv[1], sys.argv[2]
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
os.makedirs(out, exist_ok=True)


def history(path):
    return {round(float(r["t"]), 9): r for r in csv.DictReader(open(path))}


def edit(text, key, value):
    return re.sub(rf"(?m)^{key} = \S+", f"{key} = {value}", text)


rows = []
for case in ["friction-plane", "friction-roller"]:
    base = open(os.path.join(root, "scenes", f"{case}.toml")).read()
    for zeta in ["1e-1", "1e-2", "1e-4", "1e-6"]:
        for omega in ["1e-1", "1e-2", "1e-4"]:
            scene = edit(edit(base, "omega", omega), "zeta", zeta)
            ida = os.path.join(out, f"ida-{case}-{zeta}-{omega}")
            if not os.path.exists(os.path.join(ida, "history.csv")):
                path = os.path.join(out, "ida.toml")
                open(path, "w").write(scene)
                subprocess.run([anm, "reference", "ida", path, "--rtol", "1e-10",
                                "--atol", "1e-10", "-o", ida], capture_output=True, check=True)
            for order in [10, 12, 15, 20]:
                for eps in ["1e-8", "1e-10"]:
                    name = f"{case}-{zeta}-{omega}-{order}-{eps}"
                    path = os.path.join(out, name + ".toml")
                    open(path, "w").write(edit(edit(scene, "order", order), "eps", eps))
                    run = os.path.join(out, "run-" + name)
                    subprocess.run([anm, "run", path, "-o", run, "--quiet"], capture_output=True)
                    s = json.load(open(os.path.join(run, "summary.json")))
                    a, b = history(os.path.join(run, "history.csv")), history(os.path.join(ida, "history.csv"))
                    ts = [t for t in sorted(set(a) & set(b)) if case == "friction-plane" or t <= 2.25]
                    # A run stopped at the start has no error to show (nan).
                    err = max((max(abs(float(a[t][c]) - float(b[t][c])) for t in ts)
                               / (max(abs(float(b[t][c])) for t in ts) or float("nan"))
                               for c in ["ux", "uy"]), default=float("nan"))
                    row = (case, zeta, omega, order, eps, s["stop"]["reason"], s["stop"]["t"],
                           s["steps"], s["factorizations"], err)
                    rows.append(row)
                    print(*row, flush=True)
plane = [r for r in rows if r[0] == "friction-plane"]
roller = [r for r in rows if r[0] == "friction-roller"]
print(f"friction-plane: {sum(r[5] == 'end' for r in plane)} of {len(plane)} runs reach the end; "
      f"max error of those {max(r[9] for r in plane if r[5] == 'end'):.1e}")
print(f"friction-roller: {sum(r[5] != 'end' and r[6] < 2.2 for r in roller)} of {len(roller)} runs stop "
      f"before t = 2.2 s; max error (t <= 2.25 s) of the others "
      f"{max(r[9] for r in roller if not (r[5] != 'end' and r[6] < 2.2)):.1e}")
