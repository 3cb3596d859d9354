#!/usr/bin/env bash
# SIGINT during `vcar segment`: exit code 4, and the output folder holds the complete previous
# output (byte for byte) or nothing, never a partial file (a failed external-segmenter
# round's request folder, requests/, is kept for inspection by design and is not an output). Usage: sigint_segment.sh VCAR DATASET WORK
set -euo pipefail
vcar="$1"; ds="$2"; work="$3"
rm -rf "$work"; mkdir -p "$work"
view=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['reference_view'])" "$ds/prompt.json")
common=(--quiet segment --scene "$ds/scene.ply" --cameras "$ds/cameras.json" --prompt-view "$view")
printf '#!/bin/sh\nsleep 60\n' > "$work/slow_segmenter.sh"; chmod +x "$work/slow_segmenter.sh"

interrupt() {  # runs vcar with the slow segmenter into $1, sends SIGINT after 2 s, returns its code
  "$vcar" "${common[@]}" --segmenter-cmd "$work/slow_segmenter.sh" --points 10,10 --out "$1" &
  local pid=$!
  sleep 2
  kill -INT "$pid"
  local rc=0
  wait "$pid" || rc=$?
  echo "$rc"
}

# 1. A complete previous output survives an interrupted run unchanged.
"$vcar" "${common[@]}" --masks "$ds/masks" --out "$work/out"
(cd "$work/out" && sha256sum * > "$work/before.sha")
rc=$(interrupt "$work/out")
[ "$rc" = 4 ] || { echo "expected exit code 4 after SIGINT, got $rc"; exit 1; }
(cd "$work/out" && sha256sum -c --quiet "$work/before.sha") || { echo "previous output changed"; exit 1; }
# requests/ holds the interrupted round's request for inspection (docs/cli.md), not an output.
extra=$(ls -A "$work/out" | grep -v -x -F -f <(awk '{print $2}' "$work/before.sha") | grep -v -x requests || true)
[ -z "$extra" ] || { echo "extra files: $extra"; exit 1; }

# 2. A fresh output folder stays empty (or absent).
rc=$(interrupt "$work/fresh")
[ "$rc" = 4 ] || { echo "expected exit code 4 after SIGINT, got $rc"; exit 1; }
if [ -d "$work/fresh" ] && [ -n "$(ls -A "$work/fresh" | grep -v -x requests)" ]; then echo "fresh output not empty: $(ls -A "$work/fresh")"; exit 1; fi
echo "sigint: ok"
