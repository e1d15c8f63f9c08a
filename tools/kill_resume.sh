#!/usr/bin/env bash
# Kill a `--run-dir` run with SIGKILL during ingest, during the tile stage
# and during the write, rerun it after each, and compare the mesh with an
# uninterrupted run's (byte for byte) and the total work (CPU seconds of
# every process, killed ones included) with the uninterrupted run's.
#   tools/kill_resume.sh INPUT [extra reconstruct args...]
set -euo pipefail
cd "$(dirname "$0")/.."
INPUT=$(realpath "$1"); shift
EXTRA=("$@")
cargo build --release --quiet
BIN=$(realpath "${CARGO_TARGET_DIR:-target}/release/scanmesh")
WORK=$(mktemp -d "${TMPDIR:-/tmp}/scanmesh-kill.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"

# CPU seconds (user + sys) of one command, from /usr/bin/time.
cpu_of() { awk '/User time/ { u = $4 } /System time/ { s = $4 } END { print u + s }' "$1"; }

run() { # log, args...: runs reconstruct in the background under time -v
  local log=$1; shift
  /usr/bin/time -v "$BIN" reconstruct "$INPUT" --closed "${EXTRA[@]}" -q "$@" 2>"$log" &
  PID=$!
}

run plain.time -o plain.ply
wait "$PID"
FULL=$(cpu_of plain.time)
WALL=$(awk -F': ' '/Elapsed/ { print $2 }' plain.time)
echo "uninterrupted: ${FULL} CPU s, wall ${WALL}"

# Waits until the run's log or files show `moment`, then kills the run.
kill_at() { # moment, dir
  local moment=$1 dir=$2 total=""
  for _ in $(seq 1 6000); do
    case $moment in
      # Into the ingest's scatter: the partial store holds (on disk, not
      # its sparse size) a third of the input's bytes.
      ingest) [ "$(du -sB1 "$dir/store.partial" 2>/dev/null | cut -f1 || echo 0)" -ge "$(( $(stat -c %s "$INPUT") / 3 ))" ] && break ;;
      tiles) [ "$(ls "$dir/tiles/marching-cubes" 2>/dev/null | wc -l)" -ge 30 ] && break ;;
      # The mesh streams out as tiles are stitched; after the last tile is
      # saved come the last seams, the hole patches, the piece filter and
      # the faces: a short window, hence the fast polling.
      write) [ -z "${total:-}" ] && [ -e "$dir/store/manifest.json" ] && total=$(tiles "$dir")
             [ "$(ls "$dir/tiles/marching-cubes" 2>/dev/null | grep -c '\.tile$')" -ge "${total:-999999}" ] && break ;;
    esac
    sleep 0.01
  done
  # SIGKILL the scanmesh process itself (time -v is its parent).
  pkill -KILL -P "$PID" -x scanmesh || true
  wait "$PID" 2>/dev/null || true
}

tiles() { python3 -c "import json,sys; print(len(json.load(open('$1/store/manifest.json'))['tiles']))" 2>/dev/null || echo 999999; }

for moment in ${MOMENTS:-ingest tiles write}; do
  rm -rf "run-$moment" mesh.ply
  run "$moment.1.time" -o mesh.ply --run-dir "run-$moment"
  kill_at "$moment" "run-$moment"
  killed=$(cpu_of "$moment.1.time")
  if [ -e mesh.ply ]; then
    echo "$moment: the run finished before the kill landed; not counted"
    continue
  fi
  run "$moment.2.time" -o mesh.ply --run-dir "run-$moment"
  wait "$PID"
  again=$(cpu_of "$moment.2.time")
  if cmp -s plain.ply mesh.ply; then same="byte-identical"; else same="DIFFERENT"; fi
  echo "killed during $moment after ${killed} CPU s, rerun ${again} CPU s: total $(echo "$killed $again $FULL" | awk '{ printf "%.2fx", ($1 + $2) / $3 }') of uninterrupted, mesh $same"
  [ "$same" = byte-identical ] || exit 1
done

# Nothing left to do.
run noop.time -o mesh.ply --run-dir run-write
wait "$PID"
echo "rerun with nothing to do: wall $(awk -F': ' '/Elapsed/ { print $2 }' noop.time) (uninterrupted ${WALL})"
