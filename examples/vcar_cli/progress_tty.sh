#!/bin/sh
# The progress line on a terminal: runs `vcar segment` with the colour picker (sleeping 1 s
# before it writes masks) under script(1), which gives it a pty, and checks the line showed
# the frames rendered for the segmenter, the masks written, the elapsed time and an estimate.
# usage: progress_tty.sh VCAR DATASET PICKER_SCRIPT OUT
set -u
vcar=$1 ds=$2 picker=$3 out=$4
rm -rf "$out" "$out.log"
script -qec "'$vcar' segment --scene '$ds/scene.ply' --cameras '$ds/cameras.json' --prompt-view train_000 --points 80,60 --segmenter-cmd \"/usr/bin/python3 '$picker' --sleep 1\" --set enable_sss=false --out '$out'" /dev/null > "$out.log" 2>&1
for want in 'segmenter round 1, rendering: frame 8/8' 'segmenter round 1, running: masks written 0/8' ' s left' 'selected ' 'time '; do
  if ! grep -q "$want" "$out.log"; then
    echo "the terminal output lacks '$want':"
    cat "$out.log"
    exit 1
  fi
done
echo "progress line ok"
