#!/usr/bin/env python3
"""Inputs users get wrong, made from a `vcar synth` dataset, for the CLI tests (tests.cmake).

usage: make_bad_inputs.py DATASET OUT
  OUT/masks_renamed/   the dataset's masks under names that match no view (mask_000.png ...)
  OUT/masks_half/      the masks of the first half of the views only
  OUT/cameras_dup.json cameras.json with view 1 renamed like view 0
  OUT/cameras_opengl.json  cameras.json with OpenGL camera axes (x right, y up, z backward):
                       the columns y and z of each camera-to-world rotation negated
and, for several objects per run (`vcar segment --prompts`):
  OUT/prompts_oracle.json  the target and its neighbour by object_id (gt/scene.json)
  OUT/prompts_twice.json   the target twice (prompt.json's points), as "target" and "again":
                       every Gaussian is claimed by both, a tie the first object wins
  OUT/masks_objects/target/, OUT/masks_objects/again/   the dataset's masks for each
"""
import json
import os
import shutil
import sys


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 64
    ds, out = argv[1], argv[2]
    with open(os.path.join(ds, "cameras.json")) as f:
        cams = json.load(f)
    for sub in ("masks_renamed", "masks_half"):
        shutil.rmtree(os.path.join(out, sub), ignore_errors=True)
        os.makedirs(os.path.join(out, sub))
    for k, cam in enumerate(cams):
        src = os.path.join(ds, "masks", cam["img_name"] + ".png")
        shutil.copyfile(src, os.path.join(out, "masks_renamed", "mask_%03d.png" % k))
        if k < len(cams) // 2:
            shutil.copyfile(src, os.path.join(out, "masks_half", cam["img_name"] + ".png"))
    dup = json.loads(json.dumps(cams))
    dup[1]["img_name"] = dup[0]["img_name"]
    with open(os.path.join(out, "cameras_dup.json"), "w") as f:
        json.dump(dup, f)
    gl = json.loads(json.dumps(cams))
    for cam in gl:
        cam["rotation"] = [[r[0], -r[1], -r[2]] for r in cam["rotation"]]
    with open(os.path.join(out, "cameras_opengl.json"), "w") as f:
        json.dump(gl, f)

    with open(os.path.join(ds, "prompt.json")) as f:
        prompt = json.load(f)
    with open(os.path.join(ds, "gt", "scene.json")) as f:
        world = json.load(f)
    ref = prompt["reference_view"]
    with open(os.path.join(out, "prompts_oracle.json"), "w") as f:
        json.dump([{"name": "target", "reference_view": ref, "object_id": world["target_id"]},
                   {"name": "neighbour", "reference_view": ref, "object_id": world["neighbour_id"]}], f)
    twice = [{"name": n, "reference_view": ref, "points": prompt["points"][:1]} for n in ("target", "again")]
    with open(os.path.join(out, "prompts_twice.json"), "w") as f:
        json.dump(twice, f)
    for name in ("target", "again"):
        d = os.path.join(out, "masks_objects", name)
        shutil.rmtree(d, ignore_errors=True)
        shutil.copytree(os.path.join(ds, "masks"), d)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
