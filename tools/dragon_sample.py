#!/usr/bin/env python3
"""A second sampler of a triangle mesh, independent of `scangen mesh`: numpy
only, area-uniform (a triangle drawn by area, a point in it by the
square-root warp), Gaussian noise of `--noise-spacing` times the expected
mean spacing along each axis, seeded. Writes binary little-endian PLY x y z
(double). The second dragon sample of issue 39's figures:

    python3 tools/dragon_sample.py ../shared/data/dragon_vrip.ply.gz -n 1000000 \
        --noise-spacing 0.1 --seed 2 -o d1m_b.ply
"""
import argparse, gzip, sys
import numpy as np


def read_ascii_ply(path):
    op = gzip.open if path.endswith(".gz") else open
    with op(path, "rt") as f:
        nv = nf = 0
        for line in f:
            w = line.split()
            if w[:2] == ["element", "vertex"]:
                nv = int(w[2])
            elif w[:2] == ["element", "face"]:
                nf = int(w[2])
            elif w and w[0] == "end_header":
                break
            elif w[:2] == ["format", "binary_little_endian"]:
                sys.exit("only ASCII PLY meshes are read")
        v = np.loadtxt(f, max_rows=nv, usecols=(0, 1, 2))
        t = np.loadtxt(f, max_rows=nf, usecols=(1, 2, 3), dtype=np.int64)
    return v, t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("-n", type=int, default=1_000_000)
    ap.add_argument("--noise-spacing", type=float, default=0.1)
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("-o", "--output", required=True)
    a = ap.parse_args()
    v, t = read_ascii_ply(a.mesh)
    rng = np.random.default_rng(a.seed)
    a_, b_, c_ = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b_ - a_, c_ - a_), axis=1)
    pick = rng.choice(len(t), size=a.n, p=area / area.sum())
    r1, r2 = np.sqrt(rng.random(a.n))[:, None], rng.random(a.n)[:, None]
    p = (1 - r1) * a_[pick] + r1 * (1 - r2) * b_[pick] + r1 * r2 * c_[pick]
    # Mean nearest-neighbour distance of n uniform points on area A:
    # 0.5 / sqrt(n / A) (Clark and Evans 1954).
    spacing = 0.5 / np.sqrt(a.n / area.sum())
    p += rng.normal(scale=a.noise_spacing * spacing, size=p.shape)
    with open(a.output, "wb") as f:
        f.write(b"ply\nformat binary_little_endian 1.0\n")
        f.write(f"comment dragon_sample.py seed {a.seed} noise {a.noise_spacing} sp\n".encode())
        f.write(f"element vertex {a.n}\nproperty double x\nproperty double y\nproperty double z\nend_header\n".encode())
        f.write(p.astype("<f8").tobytes())


if __name__ == "__main__":
    main()
