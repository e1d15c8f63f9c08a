#!/usr/bin/env bash
# Scale bench (not CI): generates N noisy points sampled from the Stanford
# dragon (or a torus when ../shared/data is absent), streaming straight to
# disk, then runs `normals` and `reconstruct` (open and --closed) under a
# memory promise, printing per-stage wall time, CPU time and RSS
# (SCANMESH_TIMINGS) and a summary row per run; fails when a run's peak RSS
# exceeds its promise.
#
#   tools/scale.sh [SIZES="10000000 30000000 100000000"]
#
# Environment: SCALE_DIR (default target/scale; inputs are kept there),
# NORMALS_MEM (256MiB), RECONSTRUCT_MEM (512MiB).
set -euo pipefail
cd "$(dirname "$0")/.."
sizes=${1:-"10000000 30000000 100000000"}
work=${SCALE_DIR:-target/scale}
normals_mem=${NORMALS_MEM:-256MiB}
recon_mem=${RECONSTRUCT_MEM:-512MiB}
mkdir -p "$work"
cargo build --release --quiet --bins
bin="${CARGO_TARGET_DIR:-target}/release"
dragon=../shared/data/dragon_vrip.ply.gz

run() { # label budget args...
  local label=$1 budget=$2
  shift 2
  local log="$work/$label.log"
  local t0 t1
  t0=$(date +%s.%N)
  if ! SCANMESH_TIMINGS=1 "$bin/peak-rss" --budget "$budget" -- "$bin/scanmesh" "$@" \
    --mem "$budget" --quiet >"$log" 2>&1; then
    cat "$log" >&2
    echo "FAILED: $label (see $log)" >&2
    return 1
  fi
  t1=$(date +%s.%N)
  grep -E '^ +[a-z:() ]+: ' "$log" | sed 's/^/    /'
  printf '%-28s %8.1f s  %s\n' "$label" "$(echo "$t1 - $t0" | bc)" \
    "$(grep -o 'peak [0-9.]*[KMG]iB' "$log" | tail -1)"
}

for n in $sizes; do
  input="$work/scan-$n.ply"
  if [ ! -f "$input" ]; then
    if [ -f "$dragon" ]; then
      "$bin/scangen" mesh --mesh "$dragon" -n "$n" --noise-spacing 0.1 -o "$input"
    else
      "$bin/scangen" torus -n "$n" --noise-spacing 0.1 -o "$input"
    fi
  fi
  "$bin/scanmesh" info --plan "$input" --mem "$normals_mem" --quiet
  run "normals-$n" "$normals_mem" normals "$input" -o "$work/normals-$n.ply"
  run "reconstruct-$n" "$recon_mem" reconstruct "$input" -o "$work/mesh-$n.ply"
  run "reconstruct-closed-$n" "$recon_mem" reconstruct "$input" -o "$work/closed-$n.ply" --closed
  rm -f "$work/normals-$n.ply" "$work/mesh-$n.ply" "$work/closed-$n.ply"
done
