#!/bin/sh
# Builds vcar's web page into examples/web/dist/ with Debian's emscripten and npm only:
#   vcar.js      vcar as WebAssembly (one file; emcmake + CMake, examples/web/CMakeLists.txt)
#   vendor/      three.js and Spark from the npm registry (versions pinned by package-lock.json)
#   index.html, app.js, worker.js, style.css (examples/web/web/)
# Environment: VCAR_WASM_BUILD (build folder, default <repo>/build-wasm), JOBS (default 2).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${VCAR_WASM_BUILD:-$root/build-wasm}
export NODE_PATH=${NODE_PATH:-/usr/share/nodejs}   # Debian's emscripten finds its node modules here
for tool in emcmake em++ npm cmake; do
  command -v "$tool" >/dev/null 2>&1 || { echo "build.sh: $tool not found (apt-get install emscripten cmake; Node 20 with npm)" >&2; exit 2; }
done

cd "$here"
npm ci --no-audit --no-fund --loglevel=error
emcmake cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "${JOBS:-2}"

rm -rf dist
mkdir -p dist/vendor/three/addons/controls dist/vendor/three/addons/postprocessing dist/vendor/spark dist/vendor/fzstd dist/vendor/opencv
cp web/index.html web/app.js web/worker.js web/grabcut.js web/style.css dist/
cp "$build/vcar.js" dist/
cp node_modules/three/build/three.module.js node_modules/three/build/three.core.js dist/vendor/three/
cp node_modules/three/examples/jsm/controls/OrbitControls.js dist/vendor/three/addons/controls/
cp node_modules/three/examples/jsm/postprocessing/Pass.js dist/vendor/three/addons/postprocessing/
cp node_modules/three/LICENSE dist/vendor/three/LICENSE
cp node_modules/@sparkjsdev/spark/dist/spark.module.js node_modules/@sparkjsdev/spark/LICENSE dist/vendor/spark/
cp node_modules/fzstd/umd/index.js dist/vendor/fzstd/fzstd.js   # SPZ v4's zstd streams (src/compression_stubs.cpp)
cp node_modules/fzstd/LICENSE dist/vendor/fzstd/LICENSE
cp node_modules/@techstark/opencv-js/dist/opencv.js node_modules/@techstark/opencv-js/LICENSE dist/vendor/opencv/   # GrabCut (web/grabcut.js)
echo "build.sh: $(du -sh dist | cut -f1) in $here/dist"
