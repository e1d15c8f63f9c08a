#!/usr/bin/env bash
# End to end: a run as tile jobs under GNU parallel and under Slurm writes
# the bytes a single process writes, for `reconstruct --closed` and `normals`.
#   tools/e2e_schedulers.sh INPUT [parallel|slurm|both] [TASKS]
# Slurm needs a cluster (tools/slurm-local.sh up) and a run directory on a
# filesystem every node sees (here: one node). Prints each comparison and
# exits non-zero on the first difference.
set -euo pipefail
cd "$(dirname "$0")/.."
INPUT=$(realpath "$1")
WHICH=${2:-both}
TASKS=${3:-8}
cargo build --release --quiet
BIN=$(realpath "${CARGO_TARGET_DIR:-target}/release/scanmesh")
WORK=$(mktemp -d "${TMPDIR:-/tmp}/scanmesh-e2e.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"

wait_slurm() {
  while squeue -h 2>/dev/null | grep -q .; do sleep 2; done
}

check() { # name, command args...
  local name=$1; shift
  local out=$1; shift
  local ext=${out##*.}
  "$BIN" "$@" -o "plain.$ext" -q >/dev/null
  for kind in parallel slurm; do
    [ "$WHICH" = both ] || [ "$WHICH" = "$kind" ] || continue
    rm -rf "run-$kind" "$kind.$ext"
    "$BIN" "$@" -o "$kind.$ext" --run-dir "run-$kind" --emit "$kind" --tasks "$TASKS" >"$kind.sh"
    local t0=$SECONDS
    if [ "$kind" = parallel ]; then
      SCANMESH=$BIN JOBS=4 sh "$kind.sh" >/dev/null 2>"$kind.err"
    else
      SCANMESH=$BIN bash "$kind.sh" >/dev/null
      wait_slurm
    fi
    if cmp -s "plain.$ext" "$kind.$ext"; then
      peak=$(grep -o 'peak [0-9.]*[KMG]iB' "run-$kind/log.txt" | sort -k2 -h | tail -1)
      echo "$name via $kind ($TASKS tasks a stage): byte-identical ($((SECONDS - t0)) s; $(grep -c ' done ' "run-$kind/log.txt") jobs, largest $peak)"
    else
      echo "$name via $kind: DIFFERS from the single-process run" >&2
      "$BIN" status "run-$kind" >&2 || true
      exit 1
    fi
  done
}

check "reconstruct --closed" mesh.ply reconstruct "$INPUT" --closed --mem 512MiB
check "normals" normals.ply normals "$INPUT" --mem 256MiB
