"""Side-by-side accuracy and time: `scanmesh reconstruct` (open and --closed)
against Open3D Poisson on the same points, in one run (issue 19).

Not part of CI (needs Open3D: `pip install open3d`, and a reference mesh):

    python3 tools/implicit_vs_poisson.py d1m.ply dragon_vrip.ply.gz \
        --spacing 1.365e-4 [--scanmesh target/release/scanmesh] \
        [--depth 9] [--repeat 3] [--extra '--cell 2e-4'] [--skip-peer] \
        [--normals-given --peer-input d1m_normals.ply]

Runs are back to back, alternating, `--repeat` times, the machine's
one-minute load printed before each (quote figures from an idle machine);
times are wall and CPU (user + sys of the child) medians, and the ratio is
of the wall medians, the figure issue 43 asks for. Normals: reconstruct
computes them from the bare points; Open3D estimates and orients its own,
unless `--normals-given` hands it the input's (write them first with
`scanmesh normals in.ply -o in_n.ply` and pass that file as `--peer-input`). Distances come
from `scanmesh eval --reference`, both ways, averaged, and are printed in
units of `--spacing` (the *input's* mean nearest-neighbour distance), not
the reference's spacing `eval` uses. `p99.9` is the larger of the two
directions' 99.9th percentiles: the tail without the last thousandth,
which one feature the sampling missed sets alone (on the 1M dragon, a
filament near (0.0341, 0.0653, -0.0003) that no run reconstructs sets
every Hausdorff; `eval` prints where each maximum lies).
"""

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def timed(cmd):
    """Wall and CPU (user + sys of the child) seconds of one run."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def evaluate(scanmesh, mesh, reference, spacing):
    out = subprocess.run(
        [scanmesh, "eval", mesh, "--reference", reference, "--json"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    d = json.loads(out)
    dist, q = d["distance"], d["quality"]
    there = dist["mesh_to_reference"]["absolute"]["mean"]
    back = dist["reference_to_mesh"]["absolute"]["mean"]
    tail = max(
        dist["mesh_to_reference"]["absolute"]["p999"],
        dist["reference_to_mesh"]["absolute"]["p999"],
    )
    return {
        "mean_sp": 0.5 * (there + back) / spacing,
        "p999_sp": tail / spacing,
        "there_sp": there / spacing,
        "back_sp": back / spacing,
        "hausdorff_sp": dist["hausdorff"] / spacing,
        "quality": q,
    }


def summary(q):
    keys = ["components", "boundary_loops", "non_manifold_edges", "non_manifold_vertices", "watertight"]
    return ", ".join(f"{k} {q[k]}" for k in keys if k in q)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("input")
    ap.add_argument("reference")
    ap.add_argument("--spacing", type=float, required=True)
    ap.add_argument("--scanmesh", default=os.path.join(HERE, "..", "target", "release", "scanmesh"))
    ap.add_argument("--depth", type=int, default=9)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--extra", default="", help="extra reconstruct options")
    ap.add_argument("--skip-peer", action="store_true")
    ap.add_argument("--normals-given", action="store_true", help="Poisson reads the normals of --peer-input")
    ap.add_argument("--peer-input", help="the peer's input (default: the same file)")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="implicit_vs_poisson_")
    extra = a.extra.split()
    runs = {
        "scanmesh open": [a.scanmesh, "reconstruct", a.input, "-q", "-o", f"{tmp}/open.ply", *extra],
        "scanmesh --closed": [
            a.scanmesh, "reconstruct", a.input, "-q", "--closed", "-o", f"{tmp}/closed.ply", *extra,
        ],
    }
    meshes = {"scanmesh open": f"{tmp}/open.ply", "scanmesh --closed": f"{tmp}/closed.ply"}
    if not a.skip_peer:
        peer = f"open3d poisson d{a.depth}"
        runs[peer] = [
            sys.executable, os.path.join(HERE, "open3d_peer.py"), "poisson", a.peer_input or a.input,
            f"{tmp}/poisson.ply", "--depth", str(a.depth),
        ] + (["--normals-given"] if a.normals_given else [])
        meshes[peer] = f"{tmp}/poisson.ply"
    times = {name: [] for name in runs}
    for _ in range(a.repeat):
        for name, cmd in runs.items():
            print(f"load {os.getloadavg()[0]:.2f} before {name}", file=sys.stderr)
            times[name].append(timed(cmd))
    cpu = {name: statistics.median(c for _, c in ts) for name, ts in times.items()}
    wall = {name: statistics.median(w for w, _ in ts) for name, ts in times.items()}
    peer_time = wall[peer] if not a.skip_peer else None
    print(f"input {a.input}, distances in input spacings ({a.spacing:g}), both ways averaged")
    print(f"{'run':<22} {'mean':>7} {'there':>7} {'back':>7} {'p99.9':>7} {'hausd.':>7} {'wall':>7} {'cpu':>7} {'ratio':>6}  mesh")
    for name in runs:
        e = evaluate(a.scanmesh, meshes[name], a.reference, a.spacing)
        t = cpu[name]
        ratio = f"{wall[name] / peer_time:.2f}" if peer_time else "-"
        print(
            f"{name:<22} {e['mean_sp']:7.4f} {e['there_sp']:7.4f} {e['back_sp']:7.4f} "
            f"{e['p999_sp']:7.2f} {e['hausdorff_sp']:7.2f} {wall[name]:6.2f}s {t:6.2f}s {ratio:>6}  {summary(e['quality'])}"
        )
    print(f"times: medians of {a.repeat} alternating runs, ratio of wall times: " + "; ".join(
        f"{n} {', '.join(f'{w:.2f}/{c:.2f}' for w, c in ts)}" for n, ts in times.items()))


if __name__ == "__main__":
    main()
