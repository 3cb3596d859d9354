#!/usr/bin/env bash
# The field through the command line (issue 46): the example stage of the three shared captures,
# forward rig at 640x480, each object the target in turn, masks from a segmenter prompted with
# the box of the target's visible ground truth on the reference view (what a user would drag;
# the other frames' boxes lifted from it); the default preset against the paper's (nvos). Prints
# one line per run and writes OUT/results.csv (seed, target, segmenter, preset, seconds, the
# `vcar eval --json` object with ';' for ',').
#   [SEGMENTER=grabcut|isnet] benchmarks/field/stage_grabcut.sh build/examples/vcar OUT [SEEDS...]   (default seed 1)
# SEGMENTER=isnet runs ISNet (examples/segmenters/isnet, install.sh first; about 6 s a frame, so
# not in bench_field's grid). The in-process driver with every preset, peer, rig and seed split
# is benchmarks/bench_field.cpp (docs/results.md, "Field"); its GrabCut rows of seed 1 are
# within 0.002 (3D F1) of this script's (docs/notes/field-2026-11-27.md).
set -u
V=$(realpath "$1"); W=$2; shift 2
SEEDS=${*:-1}
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
S=$ROOT/examples/stages/three_objects.json
SEG=${SEGMENTER:-grabcut}
case $SEG in
  grabcut) SEGARGS=(--segmenter grabcut) ;;
  isnet) SEGARGS=(--segmenter-cmd "node $ROOT/examples/segmenters/isnet/isnet.mjs") ;;
  *) echo "SEGMENTER must be grabcut or isnet" >&2; exit 2 ;;
esac
mkdir -p "$W"
echo "seed,target,segmenter,preset,seconds,json" > "$W/results.csv"
for seed in $SEEDS; do
  for t in biker guitar donut; do
    D=$W/s${seed}_$t
    [ -f "$D/prompt.json" ] || "$V" synth --stage "$S" --seed "$seed" --target "$t" --rig forward --width 640 --height 480 --out "$D" > /dev/null
    ref=$(/usr/bin/python3 -c "import json,sys;print(json.load(open(sys.argv[1]))['reference_view'])" "$D/prompt.json")
    box=$(/usr/bin/python3 -c "import json,sys;print(','.join(str(int(round(v))) for v in json.load(open(sys.argv[1]))['box']))" "$D/prompt.json")
    for preset in robust nvos; do
      O=$D/out_${SEG}_$preset
      t0=$(date +%s.%N)
      "$V" segment --scene "$D/scene.ply" --cameras "$D/cameras.json" --images "$D/images" --prompt-view "$ref" \
        --box "$box" "${SEGARGS[@]}" --preset "$preset" --out "$O" > "$O.log" 2>&1 || { echo "FAIL $seed $t $SEG $preset"; tail -3 "$O.log"; continue; }
      t1=$(date +%s.%N)
      j=$("$V" eval --dataset "$D" --selection "$O/selection.json" --json | tr -d '\n' | sed 's/,/;/g')
      echo "$seed,$t,$SEG,$preset,$(echo "$t1 - $t0" | bc),$j" >> "$W/results.csv"
      echo "$seed $t $SEG $preset $(echo "$t1 - $t0" | bc)s"
    done
  done
done
