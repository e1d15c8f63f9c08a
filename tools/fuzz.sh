#!/usr/bin/env bash
# Runs every cargo-fuzz target for SECONDS each (default 900), seeded with
# fuzz/seeds/<target>; crashes land in fuzz/artifacts/<target>/ and each one
# becomes a named regression test. Needs nightly and cargo-fuzz
# (`cargo install cargo-fuzz`). Not part of CI.
#   tools/fuzz.sh [SECONDS] [TARGET ...]
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
secs=${1:-900}
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  mapfile -t targets < <(cargo +nightly fuzz list)
fi
status=0
for t in "${targets[@]}"; do
  mkdir -p "corpus/$t"
  cp -n seeds/"$t"/* "corpus/$t/" 2>/dev/null || true
  echo "== $t for ${secs}s"
  # rss_limit: a reader must never allocate by an untrusted count.
  if ! cargo +nightly fuzz run -O "$t" "corpus/$t" -- \
      -max_total_time="$secs" -rss_limit_mb=1024 -timeout=10 -max_len=65536; then
    echo "!! $t: finding in fuzz/artifacts/$t" >&2
    status=1
  fi
done
exit $status
