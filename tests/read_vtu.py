#!/usr/bin/env python3
"""Reads ricochet's field output with a real VTK reader (meshio) and reports what it found.

Usage: python3 tests/read_vtu.py OUT_DIR

For OUT_DIR/fields.pvd and every OUT_DIR/fields/*.vtu it prints one JSON object per line:
  {"pvd": N, "files": [...], "times": [...], "missing": [...]}
  {"file": NAME, "points": N, "cells": M, "cell_types": [...], "point_data": {name: ncomp},
   "cell_data": {name: ncomp}, "reference_bbox": [xmin, ymin, xmax, ymax],
   "von_mises_mismatch": x, "max_abs_z": z}
"reference_bbox" is the bounding box of (deformed points - displacement), i.e. of the reference
mesh; "von_mises_mismatch" is the largest relative difference between the written von Mises
stress and the one recomputed from the written stress tensor (in double precision).

Exit status: 0 on success, 77 when meshio cannot be imported, 1 on any read error.
"""
import json
import os
import sys
import xml.etree.ElementTree as ET

try:
    import meshio
    import numpy as np
except ImportError as e:  # pragma: no cover - depends on the machine
    print(f"SKIP: cannot import meshio ({e})", file=sys.stderr)
    sys.exit(77)


def ncomp(a):
    a = np.asarray(a)
    return 1 if a.ndim == 1 else int(a.shape[1])


def main(out_dir):
    pvd = os.path.join(out_dir, "fields.pvd")
    root = ET.parse(pvd).getroot()
    sets = root.findall("./Collection/DataSet")
    files = [d.get("file") for d in sets]
    times = [float(d.get("timestep")) for d in sets]
    missing = [f for f in files if not os.path.isfile(os.path.join(out_dir, f))]
    print(json.dumps({"pvd": len(sets), "files": files, "times": times, "missing": missing}))
    field_dir = os.path.join(out_dir, "fields")
    for name in sorted(os.listdir(field_dir)):
        if not name.endswith(".vtu"):
            continue
        mesh = meshio.read(os.path.join(field_dir, name))
        cells = sum(len(b.data) for b in mesh.cells)
        types = sorted({b.type for b in mesh.cells})
        pd = {k: ncomp(v) for k, v in mesh.point_data.items()}
        cd = {k: ncomp(v[0]) for k, v in mesh.cell_data.items()}
        pts = np.asarray(mesh.points, dtype=np.float64)
        ref = pts[:, :2] - np.asarray(mesh.point_data["displacement"], dtype=np.float64)[:, :2]
        # Cell data comes in one block per run of cells of one type (quads, triangles).
        s = np.concatenate([np.asarray(b, dtype=np.float64) for b in mesh.cell_data["stress"]])
        sxx, syy, sxy, szz = s[:, 0], s[:, 1], s[:, 2], s[:, 3]
        vm = np.sqrt(0.5 * ((sxx - syy) ** 2 + (syy - szz) ** 2 + (szz - sxx) ** 2 + 6 * sxy**2))
        vm_file = np.concatenate(
            [np.asarray(b, dtype=np.float64).reshape(-1) for b in mesh.cell_data["von_mises"]]
        )
        scale = max(float(np.max(np.abs(vm))), 1e-300)
        print(
            json.dumps(
                {
                    "file": name,
                    "points": int(len(pts)),
                    "cells": int(cells),
                    "cell_types": types,
                    "point_data": pd,
                    "cell_data": cd,
                    "reference_bbox": [
                        float(ref[:, 0].min()),
                        float(ref[:, 1].min()),
                        float(ref[:, 0].max()),
                        float(ref[:, 1].max()),
                    ],
                    "von_mises_mismatch": float(np.max(np.abs(vm - vm_file)) / scale),
                    "max_abs_z": float(np.max(np.abs(pts[:, 2]))),
                }
            )
        )


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    try:
        main(sys.argv[1])
    except Exception as e:  # report, do not hide
        print(f"ERROR: {type(e).__name__}: {e}", file=sys.stderr)
        sys.exit(1)
