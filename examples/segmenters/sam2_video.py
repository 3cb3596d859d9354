#!/usr/bin/python3
"""SAM 2 in video mode behind the vcar external-segmenter protocol (docs/cli.md).

    sam2_video.py --checkpoint CKPT --config CFG [--device cuda] [--keep-all] REQUEST_DIR

The request's frames are a video that starts at the reference view (frame 0): the prompt
(points and/or box of prompt.json, pixels of frame 0) is added on frame 0 and SAM 2 propagates
the object through all frames; masks/NNNNN.png gets the mask of every frame where the object
is found (an empty mask is not written unless --keep-all: a missing file means "no mask").
Needs torch, Pillow, numpy and the `sam2` package (https://github.com/facebookresearch/sam2);
not run in CI. Text prompts are not supported by SAM 2 (use a grounding model to make a box).
"""
import argparse
import json
import os
import shutil
import sys
import tempfile


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
    points = np.array(prompt.get("points") or [], dtype=np.float32).reshape(-1, 2)
    labels = np.array(prompt.get("point_labels") or [], dtype=np.int32)
    box = np.array(prompt["box"], dtype=np.float32) if prompt.get("box") else None
    if len(points) == 0 and box is None:
        print("sam2_video: needs points or a box on frame 0 (text is not supported)", file=sys.stderr)
        return 2

    # SAM 2's video loader reads a folder of JPEG frames named by their index.
    video = tempfile.mkdtemp(prefix="vcar-sam2-")
    try:
        for k, cam in enumerate(cams):
            img = Image.open(os.path.join(a.request, "frames", cam["img_name"] + ".png")).convert("RGB")
            img.save(os.path.join(video, "%05d.jpg" % k), quality=95)
        predictor = build_sam2_video_predictor(a.config, a.checkpoint, device=a.device)
        os.makedirs(os.path.join(a.request, "masks"), exist_ok=True)
        with torch.inference_mode(), torch.autocast(a.device, dtype=torch.bfloat16, enabled=a.device == "cuda"):
            state = predictor.init_state(video_path=video)
            predictor.add_new_points_or_box(
                inference_state=state, frame_idx=0, obj_id=1,
                points=points if len(points) else None,
                labels=labels if len(points) else None,
                box=box)
            written = 0
            for frame_idx, obj_ids, logits in predictor.propagate_in_video(state):
                mask = (logits[0] > 0.0).squeeze().cpu().numpy().astype(np.uint8) * 255
                if not mask.any() and not a.keep_all:
                    continue
                out = os.path.join(a.request, "masks", cams[frame_idx]["img_name"] + ".png")
                Image.fromarray(mask, mode="L").save(out + ".part.png")
                os.replace(out + ".part.png", out)
                written += 1
        print("sam2_video: %d of %d frames have a mask" % (written, len(cams)))
    finally:
        shutil.rmtree(video, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
