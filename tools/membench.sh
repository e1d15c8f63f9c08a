#!/usr/bin/env bash
# Memory-budget bench: generates N points sampled from the Stanford dragon
# (or a torus when ../shared/data is absent), runs `scanmesh normals` under
# `peak-rss` with --mem BUDGET, and fails when the peak RSS exceeds it.
#
#   tools/membench.sh [N=10000000] [BUDGET=256MiB] [COMMAND=normals]
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-10000000}
budget=${2:-256MiB}
cmd=${3:-normals}
work=${MEMBENCH_DIR:-target/membench}
mkdir -p "$work"
cargo build --release --quiet --bins
bin="${CARGO_TARGET_DIR:-target}/release"
input="$work/scan-$n.ply"
if [ ! -f "$input" ]; then
  dragon=../shared/data/dragon_vrip.ply.gz
  if [ -f "$dragon" ]; then
    "$bin/scangen" mesh --mesh "$dragon" -n "$n" --noise-spacing 0.1 -o "$input"
  else
    "$bin/scangen" torus -n "$n" --noise-spacing 0.1 -o "$input"
  fi
fi
case "$cmd" in
  normals) out="$work/out.ply" ;;
  reconstruct) out="$work/mesh.ply" ;;
  *) echo "unknown command $cmd" >&2; exit 2 ;;
esac
"$bin/peak-rss" --budget "$budget" -- "$bin/scanmesh" "$cmd" "$input" -o "$out" --mem "$budget" --quiet
