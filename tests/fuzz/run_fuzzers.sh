#!/usr/bin/env bash
# Runs every fuzz target for a fixed time. Usage:
#   tests/fuzz/run_fuzzers.sh <build dir configured with -DVCAR_FUZZ=ON> [seconds per target=180] [targets...]
# New corpus entries go to <build>/fuzz-work/<target>/corpus (the seeds in tests/fuzz/corpus stay
# as they are); crashes, leaks, timeouts and out-of-memory inputs to <build>/fuzz-work/<target>/.
# Exit status 1 when any target found something.
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="${1:?usage: run_fuzzers.sh <build dir> [seconds] [targets...]}"
secs="${2:-180}"
shift $(( $# >= 2 ? 2 : 1 ))
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(ply colmap_bin colmap_txt cameras_json transforms_json mask_png splat spz compressed_ply)
status=0
for t in "${targets[@]}"; do
  exe="$build/tests/fuzz/fuzz_$t"
  [ -x "$exe" ] || { echo "missing $exe (build the fuzz_$t target)"; status=1; continue; }
  work="$build/fuzz-work/$t"
  mkdir -p "$work/corpus"
  echo "== fuzz_$t: ${secs}s"
  # -rss_limit_mb / -malloc_limit_mb: a lying size field must fail before allocating.
  if ! "$exe" -max_total_time="$secs" -rss_limit_mb=512 -malloc_limit_mb=512 -timeout=10 \
       -max_len=16384 -print_final_stats=1 -artifact_prefix="$work/" \
       "$work/corpus" "$here/corpus/$t" > "$work/log.txt" 2>&1; then
    status=1
    echo "   FOUND SOMETHING: see $work/log.txt and $work/crash-* / leak-* / oom-* / timeout-*"
  fi
  grep -E "^(stat::number_of_executed_units|stat::peak_rss_mb|#[0-9]+.*DONE)" "$work/log.txt" | tr '\n' ' '; echo
done
exit $status
