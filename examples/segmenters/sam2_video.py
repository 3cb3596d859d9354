#!/usr/bin/python3
"""SAM 2 in video mode behind the vcar external-segmenter protocol (docs/cli.md).

    sam2_video.py --checkpoint CKPT --config CFG [--device cuda] [--keep-all] REQUEST_DIR

The request's frames are a video that starts at the reference view (frame 0): the prompt
(points and/or box of prompt.json, pixels of frame 0) is added on frame 0 and SAM 2 propagates
the object through all frames; masks/NNNNN.png gets the mask of every frame where the object
is found (an empty mask is not written unless --keep-all: a missing file means "no mask").

Several objects (prompt.json "objects", `vcar segment --prompts`): each object is asked about
its frames ("frames": [first, count]) with its prompt on frame "frame"; objects that share the
same frames (the coarse round: every object, every frame) are tracked together in one video,
and each different run of frames (the batched fine round: each object's own renders) is a video
of its own. The model is loaded once per request. Masks go to masks/<name>/NNNNN.png.

Needs torch, Pillow, numpy and the `sam2` package (https://github.com/facebookresearch/sam2);
not run in CI. Text prompts are not supported by SAM 2 (use a grounding model to make a box).
"""
import argparse
import json
import os
import shutil
import sys
import tempfile


def prompt_arrays(np, p):
    points = np.array(p.get("points") or [], dtype=np.float32).reshape(-1, 2)
    labels = np.array(p.get("point_labels") or [], dtype=np.int32)
    box = np.array(p["box"], dtype=np.float32) if p.get("box") else None
    return points, labels, box


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--checkpoint", required=True, help="e.g. sam2.1_hiera_large.pt")
    ap.add_argument("--config", required=True, help="e.g. configs/sam2.1/sam2.1_hiera_l.yaml")
    ap.add_argument("--device", default="cuda")
    ap.add_argument("--keep-all", action="store_true", help="also write empty masks")
    ap.add_argument("request", help="request directory (appended by vcar)")
    a = ap.parse_args()

    import numpy as np
    import torch
    from PIL import Image
    from sam2.build_sam import build_sam2_video_predictor

    with open(os.path.join(a.request, "prompt.json")) as f:
        prompt = json.load(f)
    with open(os.path.join(a.request, "cameras.json")) as f:
        cams = json.load(f)
    objects = prompt.get("objects")
    if objects is None:  # one object: its prompt on frame 0, every frame, masks in masks/
        objects = [dict(prompt, name="", frame=0, frames=[0, len(cams)])]
    for obj in objects:
        points, _, box = prompt_arrays(np, obj)
        if len(points) == 0 and box is None:
            print("sam2_video: object %r needs points or a box (text is not supported)" % obj["name"], file=sys.stderr)
            return 2
    # Objects grouped by their frames: one video each.
    videos = {}
    for obj in objects:
        first, count = obj.get("frames", [0, len(cams)])
        videos.setdefault((first, count), []).append(obj)

    predictor = build_sam2_video_predictor(a.config, a.checkpoint, device=a.device)
    written = 0
    for (first, count), objs in videos.items():
        # SAM 2's video loader reads a folder of JPEG frames named by their index.
        video = tempfile.mkdtemp(prefix="vcar-sam2-")
        try:
            for i in range(count):
                cam = cams[first + i]
                img = Image.open(os.path.join(a.request, "frames", cam["img_name"] + ".png")).convert("RGB")
                img.save(os.path.join(video, "%05d.jpg" % i), quality=95)
            for obj in objs:
                os.makedirs(os.path.join(a.request, "masks", obj["name"]), exist_ok=True)
            with torch.inference_mode(), torch.autocast(a.device, dtype=torch.bfloat16, enabled=a.device == "cuda"):
                state = predictor.init_state(video_path=video)
                for obj_id, obj in enumerate(objs, start=1):
                    points, labels, box = prompt_arrays(np, obj)
                    predictor.add_new_points_or_box(
                        inference_state=state, frame_idx=obj["frame"] - first, obj_id=obj_id,
                        points=points if len(points) else None,
                        labels=labels if len(points) else None,
                        box=box)
                # Forward from the earliest prompt, then backward when a prompt is not on the
                # video's first frame (an object prompted on frame 3 is also in frames 0-2).
                passes = [False] + ([True] if any(obj["frame"] > first for obj in objs) else [])
                found = set()  # (frame, object) with a non-empty mask written
                for reverse in passes:
                    for frame_idx, obj_ids, logits in predictor.propagate_in_video(state, reverse=reverse):
                        for j, obj_id in enumerate(obj_ids):
                            if (frame_idx, obj_id) in found:
                                continue
                            obj = objs[obj_id - 1]
                            mask = (logits[j] > 0.0).squeeze().cpu().numpy().astype(np.uint8) * 255
                            if mask.any():
                                found.add((frame_idx, obj_id))
                            elif not a.keep_all:
                                continue
                            out = os.path.join(a.request, "masks", obj["name"], cams[first + frame_idx]["img_name"] + ".png")
                            Image.fromarray(mask, mode="L").save(out + ".part.png")
                            os.replace(out + ".part.png", out)
                            written += 1
                predictor.reset_state(state)
        finally:
            shutil.rmtree(video, ignore_errors=True)
    print("sam2_video: %d masks over %d frames, %d objects, %d videos" % (written, len(cams), len(objects), len(videos)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
