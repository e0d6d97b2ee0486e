#!/usr/bin/python3
"""Print the mesh-convergence tables of the plate-cylinder dolfinx reference.

Reads reference/data/plate-cylinder/curves_<mesh>.csv and meta_<mesh>.json
(written by plate_cylinder.py) and prints Markdown tables: uz_A, ux_A and
rn_total at lambda = 0.05, 0.1, 0.2, 0.5, 1 per mesh, and the run summary.
Usage: /usr/bin/python3 reference/dolfinx/summarize.py [data folder]
"""
import csv
import glob
import json
import os
import sys

here = os.path.dirname(os.path.abspath(__file__))
data = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "data", "plate-cylinder")
targets = [0.05, 0.1, 0.2, 0.5, 1.0]
rows = []
for path in sorted(glob.glob(os.path.join(data, "curves_*.csv"))):
    name = os.path.basename(path)[len("curves_"):-len(".csv")]
    with open(path) as f:
        recs = list(csv.DictReader(f))
    meta_path = os.path.join(data, f"meta_{name}.json")
    meta = json.load(open(meta_path)) if os.path.exists(meta_path) else {}
    at = {}
    for r in recs:
        lam = float(r["lambda"])
        for t in targets:
            if abs(lam - t) < 1e-12:
                at[t] = r
    rows.append((name, recs, meta, at))

print("| mesh | dofs | " + " | ".join(f"uz_A({t:g})" for t in targets) + " |")
print("| --- | --- | " + " | ".join("---" for _ in targets) + " |")
for name, recs, meta, at in rows:
    dofs = meta.get("mesh", {}).get("dofs", "?")
    cells = [f"{float(at[t]['uz_A']):.5f}" if t in at else "-" for t in targets]
    print(f"| {name} | {dofs} | " + " | ".join(cells) + " |")
print()
print("| mesh | lambda | uz_A [m] | ux_A [m] | rn_B [N] | rn_C [N] | rn_D [N] | rn_total [N] | zone x_lo..x_hi [m] |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for name, recs, meta, at in rows:
    for t in targets:
        if t in at:
            r = at[t]
            print(f"| {name} | {t:g} | {float(r['uz_A']):.5f} | {float(r['ux_A']):.5f} | "
                  f"{float(r['rn_B']):.4f} | {float(r['rn_C']):.4f} | {float(r['rn_D']):.4f} | "
                  f"{float(r['rn_total']):.4f} | {float(r['x_lo']):.4f}..{float(r['x_hi']):.4f} |")
print()
print("| mesh | elements x,y,z | dofs | lambda reached | steps | Newton its | run time [s] | "
      "contact start (rn_total > threshold) | cantilever ratio |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for name, recs, meta, at in rows:
    m = meta.get("mesh", {})
    lam = meta.get("lambda_reached", float(recs[-1]["lambda"]) if recs else 0.0)
    ratio = meta.get("linear_cantilever_check", {}).get("ratio")
    print(f"| {name} | {m.get('elements_xyz', '?')} | {m.get('dofs', '?')} | {lam:.4g} | "
          f"{meta.get('load_steps', len(recs) - 1)} | {meta.get('newton_iterations', '?')} | "
          f"{meta.get('run_time_s', '?')} | {meta.get('contact_start_lambda', '?')} | "
          f"{ratio if ratio is None else f'{ratio:.5f}'} |")
