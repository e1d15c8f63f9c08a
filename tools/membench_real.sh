#!/usr/bin/env bash
# Memory-budget bench on real scans: every command on every file given,
# under each budget, run by `peak-rss --budget`; fails when a peak exceeds
# its budget, prints one line per run (file, budget, command, peak, status).
# A command that stops with a clear "budget too small" error kept the
# promise; it is listed as `refused`.
#
#   tools/membench_real.sh FILE... [-- BUDGET...]   (budgets: 256MiB 512MiB)
#
# The files of issue 38's measurements are PDAL's test data (BSD):
#   git clone --depth 1 https://github.com/PDAL/PDAL && ls PDAL/test/data/{copc,las,laz}
# lone-star.copc.laz (519k points of a geyser cone, terrestrial), autzen_trim.las
# (110k, aerial town), las_with_several_extra_byte_bloc.laz, 4_6_crop.las, hexbin-crop.las.
set -uo pipefail
cd "$(dirname "$0")/.."
files=(); budgets=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do files+=("$(realpath "$1")"); shift; done
[ $# -gt 0 ] && shift
budgets=("$@"); [ ${#budgets[@]} -eq 0 ] && budgets=(256MiB 512MiB)
cargo build --release --quiet --bins || exit 1
bin=$(realpath "${CARGO_TARGET_DIR:-target}")/release
work=${MEMBENCH_DIR:-target/membench-real}
mkdir -p "$work"
failed=0
one() {
  local file=$1 budget=$2 name=$3; shift 3
  rm -rf "$work/out"; mkdir -p "$work/out"
  "$bin/peak-rss" --json --output "$work/report.json" --budget "$budget" \
    -- "$bin/scanmesh" "$@" --mem "$budget" >/dev/null 2>"$work/err"
  local rc=$? status=ok
  local peak; peak=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["peak_rss_bytes"] >> 20)' "$work/report.json" 2>/dev/null || echo "?")
  if [ $rc -eq 3 ]; then status="OVER BUDGET"; failed=1
  elif [ $rc -ne 0 ]; then
    if grep -q "the budget holds for tiles\|more than the budget holds\|budget .* too small\|smallest budget" "$work/err"; then status=refused
    else status="FAILED rc=$rc: $(tail -1 "$work/err")"; failed=1; fi
  fi
  printf '%-40s %-7s %-11s peak %5s MiB  %s\n' "$(basename "$file")" "$budget" "$name" "$peak" "$status"
}
for f in "${files[@]}"; do
  for b in "${budgets[@]}"; do
    o=$work/out
    one "$f" "$b" convert     convert "$f" "$o/c.ply"
    one "$f" "$b" tile        tile "$f" -o "$o/s"
    one "$f" "$b" normals     normals "$f" -o "$o/n.ply"
    one "$f" "$b" curvature   curvature "$f" -o "$o/k.ply"
    one "$f" "$b" features    features "$f" -o "$o/f.ply"
    one "$f" "$b" neighbors   neighbors "$f" -o "$o/nb.bin"
    one "$f" "$b" implicit    reconstruct "$f" -o "$o/r.ply"
    one "$f" "$b" closed      reconstruct "$f" -o "$o/r.ply" --closed
    one "$f" "$b" projection  reconstruct "$f" -o "$o/r.ply" --method projection
    one "$f" "$b" delaunay    reconstruct "$f" -o "$o/r.ply" --method delaunay
  done
done
exit $failed
