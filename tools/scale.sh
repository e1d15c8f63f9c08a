#!/usr/bin/env bash
# Scale bench (not CI): generates N noisy points sampled from the Stanford
# dragon (or a torus when ../shared/data is absent), streaming straight to
# disk (LAZ by default), then runs `normals` and `reconstruct` (open and
# --closed) under a memory promise, printing per-stage wall time, CPU time
# and RSS (SCANMESH_TIMINGS) and a summary row per run: wall, peak RSS,
# and the scratch directory's peak size (sampled every second) in bytes
# and bytes per point, the disk column of README "Scale". Fails when a
# run's peak RSS exceeds its promise.
#
#   tools/scale.sh [SIZES="10000000 30000000 100000000"]
#
# Environment: SCALE_DIR (default target/scale; inputs are kept there),
# SCALE_FORMAT (laz; or ply), NORMALS_MEM (256MiB), RECONSTRUCT_MEM
# (512MiB), CELL_SPACINGS (the reconstruction's --cell in mean spacings,
# from `info`'s estimate; empty: the default cell), RUNS (normals
# reconstruct closed: which to run).
set -euo pipefail
cd "$(dirname "$0")/.."
sizes=${1:-"10000000 30000000 100000000"}
work=${SCALE_DIR:-target/scale}
format=${SCALE_FORMAT:-laz}
normals_mem=${NORMALS_MEM:-256MiB}
recon_mem=${RECONSTRUCT_MEM:-512MiB}
cell_spacings=${CELL_SPACINGS:-}
runs=${RUNS:-"normals reconstruct closed"}
mkdir -p "$work"
cargo build --release --quiet --bins
bin="${CARGO_TARGET_DIR:-target}/release"
dragon=../shared/data/dragon_vrip.ply.gz

# Prints the most disk `dir` took while process `pid` ran: the blocks its
# files hold, not their apparent sizes (a column is created sparse and
# fills as it is written; a forest run is punched out once read).
scratch_peak() { # dir pid
  local peak=0 now
  while kill -0 "$2" 2>/dev/null; do
    now=$(du -s -B1 "$1" 2>/dev/null | cut -f1 || echo 0)
    [ "${now:-0}" -gt "$peak" ] && peak=$now
    sleep 1
  done
  echo "$peak"
}

run() { # label points budget args...
  local label=$1 points=$2 budget=$3
  shift 3
  local log="$work/$label.log" scratch="$work/scratch-$label"
  rm -rf "$scratch" && mkdir -p "$scratch"
  local t0 t1 pid peak status=0
  t0=$(date +%s.%N)
  SCANMESH_TIMINGS=1 "$bin/peak-rss" --budget "$budget" -- "$bin/scanmesh" "$@" \
    --mem "$budget" --scratch-dir "$scratch" --quiet >"$log" 2>&1 &
  pid=$!
  peak=$(scratch_peak "$scratch" "$pid")
  wait "$pid" || status=$?
  t1=$(date +%s.%N)
  rm -rf "$scratch"
  if [ "$status" -ne 0 ]; then
    cat "$log" >&2
    echo "FAILED: $label (see $log)" >&2
    return 1
  fi
  grep -E '^ +[a-z:() ]+: ' "$log" | sed 's/^/    /'
  printf '%-28s %8.1f s  %s  scratch peak %s B (%s B/point)\n' "$label" \
    "$(echo "$t1 - $t0" | bc)" "$(grep -o 'peak [0-9.]*[KMG]iB' "$log" | tail -1)" \
    "$peak" "$(echo "scale=1; $peak / $points" | bc)"
}

for n in $sizes; do
  input="$work/scan-$n.$format"
  if [ ! -f "$input" ]; then
    t0=$(date +%s)
    if [ -f "$dragon" ]; then
      "$bin/scangen" mesh --mesh "$dragon" -n "$n" --noise-spacing 0.1 --seed 11 -o "$input"
    else
      "$bin/scangen" torus -n "$n" --noise-spacing 0.1 --seed 11 -o "$input"
    fi
    echo "generated $input: $(du -b "$input" | cut -f1) B in $(($(date +%s) - t0)) s"
  fi
  cell=()
  if [ -n "$cell_spacings" ]; then
    sp=$("$bin/scanmesh" info "$input" --json --quiet | grep -o '"spacing_estimate": [0-9.e-]*' | cut -d' ' -f2)
    cell=(--cell "$(echo "$cell_spacings * $sp" | sed 's/e/*10^/' | bc -l)")
  fi
  "$bin/scanmesh" info --plan "$input" --mem "$normals_mem" --quiet
  for r in $runs; do
    case $r in
    normals) run "normals-$n" "$n" "$normals_mem" normals "$input" -o "$work/normals-$n.$format" ;;
    reconstruct) run "reconstruct-$n" "$n" "$recon_mem" reconstruct "$input" -o "$work/mesh-$n.ply" "${cell[@]}" ;;
    closed) run "reconstruct-closed-$n" "$n" "$recon_mem" reconstruct "$input" -o "$work/closed-$n.ply" --closed ;;
    esac
  done
  rm -f "$work/normals-$n.$format" "$work/mesh-$n.ply" "$work/closed-$n.ply"
done
