#!/usr/bin/env bash
# A first slice of the field (issue 46): the example stage of the three shared captures, forward
# rig at 640x480, each object the target in turn, masks from OpenCV's GrabCut on boxes lifted
# from the box of the target's visible ground truth on the reference view (what a user would
# drag); the default preset against the paper's (nvos). Prints one line per run and writes
# OUT/results.csv (seed, target, preset, seconds, the `vcar eval --json` object with ';' for ',').
#   benchmarks/field/stage_grabcut.sh build/examples/vcar OUT [SEEDS...]    (default seed 1)
set -u
V=$(realpath "$1"); W=$2; shift 2
SEEDS=${*:-1}
S="$(cd "$(dirname "$0")/../.." && pwd)/examples/stages/three_objects.json"
mkdir -p "$W"
echo "seed,target,preset,seconds,json" > "$W/results.csv"
for seed in $SEEDS; do
  for t in biker guitar donut; do
    D=$W/s${seed}_$t
    [ -f "$D/prompt.json" ] || "$V" synth --stage "$S" --seed "$seed" --target "$t" --rig forward --width 640 --height 480 --out "$D" > /dev/null
    ref=$(/usr/bin/python3 -c "import json,sys;print(json.load(open(sys.argv[1]))['reference_view'])" "$D/prompt.json")
    box=$(/usr/bin/python3 -c "import json,sys;print(','.join(str(int(round(v))) for v in json.load(open(sys.argv[1]))['box']))" "$D/prompt.json")
    for preset in robust nvos; do
      O=$D/out_$preset
      t0=$(date +%s.%N)
      "$V" segment --scene "$D/scene.ply" --cameras "$D/cameras.json" --images "$D/images" --prompt-view "$ref" \
        --box "$box" --segmenter grabcut --preset "$preset" --out "$O" > "$O.log" 2>&1 || { echo "FAIL $seed $t $preset"; tail -3 "$O.log"; continue; }
      t1=$(date +%s.%N)
      j=$("$V" eval --dataset "$D" --selection "$O/selection.json" --json | tr -d '\n' | sed 's/,/;/g')
      echo "$seed,$t,$preset,$(echo "$t1 - $t0" | bc),$j" >> "$W/results.csv"
      echo "$seed $t $preset $(echo "$t1 - $t0" | bc)s"
    done
  done
done
