"""scanmesh outliers against Open3D's remove_statistical_outlier on the same
file: the same rule (k nearest other points, the sample standard deviation;
Open3D counts the point itself, so it is asked for k + 1 and its scores are
k / (k + 1) of scanmesh's), so the same points should be flagged, but for
exact duplicates (Open3D drops a point whose mean distance is 0) and scores
within rounding of the threshold.

    python3 tools/outliers_vs_open3d.py SCANMESH INPUT [k] [ratio]

Prints the counts, the points flagged by one and not the other, and the
largest relative difference of the scores."""

import os
import subprocess
import sys
import tempfile

import numpy as np
import open3d as o3d


def read_ply(path):
    types = {"double": "<f8", "float": "<f4", "uchar": "u1"}
    with open(path, "rb") as f:
        header = []
        while not header or header[-1] != "end_header":
            header.append(f.readline().decode("ascii").strip())
        n = int(next(h for h in header if h.startswith("element vertex")).split()[2])
        props = [h.split() for h in header if h.startswith("property")]
        dtype = np.dtype([(p[2], types[p[1]]) for p in props])
        return np.frombuffer(f.read(), dtype=dtype, count=n)


def main():
    exe, inp = sys.argv[1], sys.argv[2]
    k = int(sys.argv[3]) if len(sys.argv) > 3 else 20
    ratio = float(sys.argv[4]) if len(sys.argv) > 4 else 2.0
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "o.ply")
        subprocess.run(
            [exe, "outliers", inp, "-o", out, "--k", str(k), "--ratio", str(ratio), "-q"],
            check=True,
        )
        ours = read_ply(out)
    xyz = np.stack([ours["x"], ours["y"], ours["z"]], axis=1)
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(xyz))
    _, kept = pcd.remove_statistical_outlier(nb_neighbors=k + 1, std_ratio=ratio)
    theirs = np.ones(len(xyz), bool)
    theirs[np.asarray(kept, dtype=np.int64)] = False
    mine = (ours["flags"] & 1) == 1
    tree = o3d.geometry.KDTreeFlann(pcd)
    worst = 0.0
    for i in range(0, len(xyz), max(1, len(xyz) // 2000)):
        _, _, d2 = tree.search_knn_vector_3d(xyz[i], k + 1)
        s = np.sqrt(np.asarray(d2)[1:]).mean()
        if s > 0:
            worst = max(worst, abs(float(ours["outlier_score"][i]) - s) / s)
    print(
        f"{os.path.basename(inp)}: {len(xyz)} points; scanmesh {mine.sum()} outliers, "
        f"Open3D {theirs.sum()}; only scanmesh {(mine & ~theirs).sum()}, "
        f"only Open3D {(theirs & ~mine).sum()}; scores' largest relative difference "
        f"{worst:.2e} (every {max(1, len(xyz) // 2000)}th point)"
    )


if __name__ == "__main__":
    main()
