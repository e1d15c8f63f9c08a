"""Open3D on the same points, for the peer figures of issues 2 and 3.

Not part of CI (Open3D is a 400 MB wheel): `pip install open3d`, then

    python3 tools/open3d_peer.py normals  in.ply out.ply  [--k 12]
    python3 tools/open3d_peer.py poisson  in.ply mesh.ply [--depth 9]
    python3 tools/open3d_peer.py bpa      in.ply mesh.ply [--k 12]

and score the outputs with `normals-eval` / `scanmesh eval --reference`.
Each command prints its own wall time per stage (reading excluded) and the
process's peak RSS, the way scanmesh's one-line summary does.
"""

import argparse
import resource
import time

import numpy as np
import open3d as o3d


def peak_mib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def oriented_normals(pcd, k):
    """estimate_normals (kNN PCA) + Hoppe's MST orientation, timed apart."""
    t0 = time.perf_counter()
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=k))
    t1 = time.perf_counter()
    pcd.orient_normals_consistent_tangent_plane(k)
    t2 = time.perf_counter()
    print(f"open3d normals: pca {t1 - t0:.2f} s, orient {t2 - t1:.2f} s, total {t2 - t0:.2f} s")
    return t2 - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("job", choices=["normals", "poisson", "bpa"])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--k", type=int, default=12)
    ap.add_argument("--depth", type=int, default=9)
    ap.add_argument(
        "--normals-given",
        action="store_true",
        help="use the input's normals (e.g. from `scanmesh normals`) instead of estimating them",
    )
    a = ap.parse_args()
    pcd = o3d.io.read_point_cloud(a.input)
    n = len(pcd.points)
    if a.normals_given:
        if not pcd.has_normals():
            raise SystemExit(f"{a.input}: --normals-given but the file has no normals")
        total = 0.0
    else:
        total = oriented_normals(pcd, a.k)
    if a.job == "normals":
        o3d.io.write_point_cloud(a.output, pcd)
    elif a.job == "poisson":
        t0 = time.perf_counter()
        mesh, _ = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(pcd, depth=a.depth)
        total += time.perf_counter() - t0
        o3d.io.write_triangle_mesh(a.output, mesh)
        print(f"open3d poisson depth {a.depth}: {len(mesh.triangles)} triangles")
    else:
        t0 = time.perf_counter()
        d = np.asarray(pcd.compute_nearest_neighbor_distance())
        r = float(np.mean(d))
        radii = o3d.utility.DoubleVector([1.5 * r, 3.0 * r])
        mesh = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(pcd, radii)
        total += time.perf_counter() - t0
        o3d.io.write_triangle_mesh(a.output, mesh)
        print(f"open3d ball pivoting radii {1.5 * r:.4g},{3.0 * r:.4g}: {len(mesh.triangles)} triangles")
    print(f"open3d {a.job}: {n} points, {total:.2f} s, peak {peak_mib():.0f}MiB")


if __name__ == "__main__":
    main()
