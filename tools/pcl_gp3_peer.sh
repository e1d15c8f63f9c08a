#!/bin/sh
# PCL's greedy projection triangulation on a PLY point file, for the
# side-by-side with `reconstruct --method projection` (issue 14): PLY ->
# PCD, normals from the 12 nearest neighbours, then GP3 with a search
# radius of 8 mean spacings and mu 2.5 (PCL's tutorial values, scaled).
# Prints each stage's CPU seconds. Not run in CI (needs pcl-tools).
# Usage: tools/pcl_gp3_peer.sh input.ply spacing workdir
set -eu
in=$1; sp=$2; dir=$3
mkdir -p "$dir"
# PCL's PointXYZ is float: a binary PCD of float x y z (scanmesh's PLY
# holds doubles, which pcl_ply2pcd does not match to x y z).
python3 - "$in" "$dir/in.pcd" <<'PY'
import sys, numpy as np
src, dst = sys.argv[1], sys.argv[2]
with open(src, "rb") as f:
    head = b""
    while not head.endswith(b"end_header\n"):
        head += f.readline()
    lines = head.decode().splitlines()
    n = int(next(l for l in lines if l.startswith("element vertex")).split()[2])
    props = [l.split()[1:] for l in lines if l.startswith("property")]
    dt = np.dtype([(name, {"double": "<f8", "float": "<f4"}[t]) for t, name in props])
    rec = np.fromfile(f, dtype=dt, count=n)
xyz = np.stack([rec["x"], rec["y"], rec["z"]], axis=1).astype("<f4")
with open(dst, "wb") as f:
    f.write(("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
             f"COUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
             f"POINTS {n}\nDATA binary\n").encode())
    f.write(xyz.tobytes())
PY
/usr/bin/time -f "pcl normal estimation: %U user %S sys %e wall %M KB" \
    pcl_normal_estimation "$dir/in.pcd" "$dir/normals.pcd" -k 12 > /dev/null
radius=$(python3 -c "print(8 * $sp)")
/usr/bin/time -f "pcl gp3: %U user %S sys %e wall %M KB" \
    pcl_gp3_surface "$dir/normals.pcd" "$dir/gp3.vtk" -radius "$radius" -mu 2.5 > /dev/null
