#!/usr/bin/env bash
# Browser vs native timing of vcar's web flow, measured in one run (docs/web.md has the table).
#   benchmarks/web/bench_web.sh [REPS]
# Needs examples/web/dist (examples/web/build.sh) and the native twin in build-web-native
# (cmake -S examples/web -B build-web-native && cmake --build build-web-native); builds a second
# WebAssembly variant without -msimd128 in build-wasm-nosimd for the SIMD comparison.
# Cases: donut.ply (45,624 trained Gaussians) with cameras.json, and without cameras (views
# around the click). Each case: the page in headless Chromium (seconds of vcar::segment in the
# worker, as the page reports them), Node with the same vcar.js, Node with the no-SIMD build,
# and the native twin with 1 thread and with all threads (OpenMP); medians of REPS runs (the
# page: one run per case).
set -euo pipefail
cd "$(dirname "$0")/../.."
REPS=${1:-3}
export NODE_PATH=/usr/share/nodejs
native=build-web-native/vcar_web_native
[ -x "$native" ] && [ -f examples/web/dist/vcar.js ] || { echo "build examples/web/dist and $native first" >&2; exit 2; }
if [ ! -f build-wasm-nosimd/vcar.js ]; then
  emcmake cmake -S examples/web -B build-wasm-nosimd -DCMAKE_BUILD_TYPE=Release -DVCAR_WASM_SIMD128=OFF >/dev/null
  cmake --build build-wasm-nosimd -j2 >/dev/null 2>&1
fi
median() { tr ' ' '\n' | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
native_time() {  # threads, args...
  local t=$1; shift; local all=""
  for _ in $(seq "$REPS"); do
    all="$all $(OMP_NUM_THREADS=$t "$native" "$@" | sed -n 's/.*"seconds": \([0-9.e-]*\).*/\1/p')"
  done
  echo "$all" | median
}
echo "| case | selected | Chromium (wasm, -msimd128) | Node (wasm, -msimd128) | Node (wasm, scalar) | native 1 thread | native $(nproc) threads | Chromium / native 1 thread |"
echo "|---|---|---|---|---|---|---|---|"
run_case() {  # name, scene, cameras|-, view|-, click
  local name=$1 scene=$2 cams=$3 view=$4 click=$5
  local targs=(--native "$PWD/$native" --scene "$PWD/$scene" --click "$click" --min-iou 0)
  local nargs=(--scene "$scene" --click "$click")
  [ "$cams" != - ] && targs+=(--cameras "$PWD/$cams") && nargs+=(--cameras "$cams")
  [ "$view" != - ] && targs+=(--view "$view") && nargs+=(--view "$view")
  local page; page=$(cd examples/web && node test/browser_test.mjs "${targs[@]}")
  local sel chrome; sel=$(echo "$page" | sed -n 's/.*"browser_selected":\([0-9]*\).*/\1/p')
  chrome=$(echo "$page" | sed -n 's/.*"browser_seconds":\([0-9.]*\).*/\1/p')
  local jac; jac=$(echo "$page" | sed -n 's/.*"jaccard":\([0-9.]*\).*/\1/p')
  local nsimd nscalar
  nsimd=$(node benchmarks/web/node_flow.cjs examples/web/dist/vcar.js "$scene" "$cams" "$view" "$click" "$REPS" | sed -n 's/.*"median_s":\([0-9.]*\).*/\1/p')
  nscalar=$(node benchmarks/web/node_flow.cjs build-wasm-nosimd/vcar.js "$scene" "$cams" "$view" "$click" "$REPS" | sed -n 's/.*"median_s":\([0-9.]*\).*/\1/p')
  local n1 nall
  n1=$(native_time 1 "${nargs[@]}")
  nall=$(native_time "$(nproc)" "${nargs[@]}")
  printf '| %s | %s (Jaccard vs native %s) | %.2f s | %.2f s | %.2f s | %.2f s | %.2f s | %.2f |\n' \
    "$name" "$sel" "$jac" "$chrome" "$nsimd" "$nscalar" "$n1" "$nall" "$(awk "BEGIN {print $chrome / $n1}")"
}
run_case "donut, cameras.json (16 views), view ring0_0" tests/data/donut.ply examples/web/test/donut_cameras.json ring0_0 160,250
run_case "donut, no cameras (16 views around the click)" tests/data/donut.ply - - 200,240
