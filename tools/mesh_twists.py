#!/usr/bin/env python3
"""Where a triangle mesh cannot be wound, and what cutting there would cost
(issue 39's Delaunay winding; numpy and scipy only, any binary PLY mesh).

Winds the mesh by a parity union-find over its edges of two triangles,
flattest crossing first (|n1 . n2| of the two unit normals, ties by the
edge's corners), so the edges it cannot wind land on the sharpest crease of
each odd cycle; then, for each such edge, the shortest odd closed walk of
triangles through it (its length and extent, and the boundary loops its
triangles touch), and the mesh after cutting the worse triangle of each
(the one whose sharpest other crossing is sharper), wound again:

    python3 tools/mesh_twists.py mesh.ply [--cycles 20]
"""
import argparse
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components


def read_ply(path):
    types = {"float": "<f4", "double": "<f8", "uchar": "u1", "int": "<i4", "uint": "<u4"}
    with open(path, "rb") as f:
        nv = nf = 0
        props, index, element = [], None, None
        while True:
            w = f.readline().decode().split()
            if w[:2] == ["element", "vertex"]:
                nv, element = int(w[2]), "v"
            elif w[:2] == ["element", "face"]:
                nf, element = int(w[2]), "f"
            elif w and w[0] == "property" and element == "v":
                props.append((w[2], types[w[1]]))
            elif w and w[0] == "property" and element == "f":
                index = types[w[3]]
            elif w == ["end_header"]:
                break
        v = np.frombuffer(f.read(nv * np.dtype(props).itemsize), dtype=props)
        face = np.dtype([("n", "u1"), ("i", index, 3)])
        t = np.frombuffer(f.read(nf * face.itemsize), dtype=face)["i"].astype(np.int64)
    return np.stack([v["x"], v["y"], v["z"]], 1).astype(np.float64), t


def dual(t, keep):
    """Pairs of kept triangles across an edge of exactly two, and whether
    they run it the same way (crossing turns the winding over)."""
    ti = np.nonzero(keep)[0]
    tt = t[ti]
    a = np.concatenate([tt[:, 0], tt[:, 1], tt[:, 2]])
    b = np.concatenate([tt[:, 1], tt[:, 2], tt[:, 0]])
    f = np.tile(np.arange(len(tt)), 3)
    key = np.minimum(a, b) * (1 << 32) + np.maximum(a, b)
    o = np.argsort(key, kind="stable")
    k = key[o]
    same = np.r_[k[1:] == k[:-1], False]
    two = same & ~np.r_[False, same[:-1]] & ~np.r_[same[1:], False]
    d = np.nonzero(two)[0]
    forward = a < b
    return ti, f[o][d], f[o][d + 1], forward[o][d] == forward[o][d + 1], k[d]


def unwound(xyz, t, keep):
    ti, f1, f2, turns, edge = dual(t, keep)
    p = xyz[t[ti]]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None] + 1e-300
    flat = np.abs((n[f1] * n[f2]).sum(1))
    parent, rel = list(range(len(ti))), [0] * len(ti)

    def find(x):
        path, p = [], 0
        while parent[x] != x:
            path.append(x)
            p ^= rel[x]
            x = parent[x]
        acc = p
        for y in path:
            r = acc
            acc ^= rel[y]
            parent[y], rel[y] = x, r
        return x, p

    bad = []
    for e in np.lexsort((edge, -flat)).tolist():
        (a, pa), (b, pb) = find(int(f1[e])), find(int(f2[e]))
        if a == b:
            if pa ^ pb != int(turns[e]):
                bad.append(e)
        else:
            parent[a], rel[a] = b, pa ^ pb ^ int(turns[e])
    bad = np.array(bad, dtype=np.int64)
    sharpest = np.full(len(t), np.inf)
    np.minimum.at(sharpest, ti[f1], flat)
    np.minimum.at(sharpest, ti[f2], flat)
    return ti[f1[bad]], ti[f2[bad]], sharpest, (ti, f1, f2, turns)


def shortest_odd(d, start):
    ti, f1, f2, turns = d
    n = len(ti)
    turns = turns.astype(np.int64)
    r = np.concatenate([f1, f1 + n])
    c = np.concatenate([f2 + n * turns, f2 + n * (1 - turns)])
    g = coo_matrix((np.ones(len(r)), (r, c)), shape=(2 * n, 2 * n)).tocsr()
    g = g + g.T
    local = np.searchsorted(ti, start)
    _, pred = breadth_first_order(g, local, directed=False, return_predecessors=True)
    if pred[local + n] < 0:
        return None
    path = [local + n]
    while path[-1] != local:
        path.append(pred[path[-1]])
    return ti[np.array(path) % n]


def loops(t, keep):
    a = np.concatenate([t[keep][:, 0], t[keep][:, 1], t[keep][:, 2]])
    b = np.concatenate([t[keep][:, 1], t[keep][:, 2], t[keep][:, 0]])
    key, count = np.unique(np.minimum(a, b) * (1 << 32) + np.maximum(a, b), return_counts=True)
    lo, hi = key[count == 1] >> 32, key[count == 1] & ((1 << 32) - 1)
    nv = int(t.max()) + 1
    _, label = connected_components(coo_matrix((np.ones(len(lo)), (lo, hi)), shape=(nv, nv)), directed=False)
    on = np.zeros(nv, bool)
    on[lo] = on[hi] = True
    return label, on, np.bincount(label[lo], minlength=label.max() + 1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("--cycles", type=int, default=20, help="odd walks to describe")
    args = ap.parse_args()
    xyz, t = read_ply(args.mesh)
    keep = np.ones(len(t), bool)
    a, b, sharpest, d = unwound(xyz, t, keep)
    print(f"{args.mesh}: {len(t)} triangles, {len(a)} edges not wound (flattest first)")
    label, on, size = loops(t, keep)
    edge = np.median(np.linalg.norm(xyz[t[:, 0]] - xyz[t[:, 1]], axis=1))
    for k in range(min(args.cycles, len(a))):
        walk = shortest_odd(d, a[k])
        if walk is None:
            continue
        centres = xyz[t[walk]].mean(1)
        extent = (centres.max(0) - centres.min(0)).max() / edge
        vs = np.unique(t[walk])
        ring = sorted({int(size[label[v]]) for v in vs[on[vs]]})
        print(f"  odd walk of {len(walk) - 1} steps, {extent:.1f} median edges across, boundary loops of {ring} edges")
    worse = np.where(sharpest[a] <= sharpest[b], a, b)
    keep[worse] = False
    a2, _, _, _ = unwound(xyz, t, keep)
    print(f"cutting the worse triangle of each: {len(np.unique(worse))} triangles, then {len(a2)} edges not wound")


if __name__ == "__main__":
    main()
