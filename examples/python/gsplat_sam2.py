#!/usr/bin/python3
"""VCAR with gsplat rendering on CUDA and SAM 2 segmenting in video mode: the wiring.

    PYTHONPATH=build/python python3 examples/python/gsplat_sam2.py \\
        --scene point_cloud.ply --cameras sparse/0 --view IMG_0001.jpg --point 512,384 \\
        --sam2-config configs/sam2.1/sam2.1_hiera_l.yaml --sam2-checkpoint sam2.1_hiera_large.pt \\
        --out object.ply

NOT RUNNABLE HERE: it needs a CUDA GPU, torch, gsplat (https://github.com/nerfstudio-project/gsplat)
and SAM 2 (https://github.com/facebookresearch/sam2), none of which are Debian packages. Its
structure is tested with stand-in callables (python/tests/test_examples.py): the tests pass a
fake `rasterization` that checks gsplat's arguments and renders with vcar's CPU renderer, and a
fake SAM 2 predictor, and check that the result equals vcar's own renderer and segmenter.

Two callables are all vcar needs (docs/python.md):
  gsplat_renderer(scene)    request -> {"rgb", "alpha", "depth"}: vcar asks it for the views it
                            renders (the training views, the sampled spiral views, renders of
                            the coarse selection alone);
  sam2_segmenter(predictor) request -> one mask per frame: frame 0 is the prompt view, so the
                            prompt goes on frame 0 and SAM 2 propagates it through the frames.
The interpreter must be the one vcar was built for (see docs/python.md for building vcar
against a virtual environment's Python).
"""
import argparse
import contextlib
import os
import shutil
import sys
import tempfile

import numpy as np

import vcar


def _numpy(x):
    """A torch tensor (any device) or an array -> numpy."""
    return x.detach().cpu().numpy() if hasattr(x, "detach") else np.asarray(x)


def gsplat_renderer(scene, device="cuda", rasterization=None, torch=None):
    """A vcar renderer on gsplat. Uploads the scene once (edit it later and make a new renderer).

    gsplat's conventions are vcar's: world-to-camera `viewmats` and `Ks` in OpenCV axes, quats
    w x y z, scales = exp(log_scales), opacities = sigmoid(logits), SH colours (N, K, 3), a
    0.3 px^2 low-pass, expected depth sum z alpha T in "RGB+D" mode."""
    if torch is None:
        import torch
    if rasterization is None:
        from gsplat import rasterization

    def tensor(a):
        return torch.as_tensor(np.ascontiguousarray(a), device=device)

    means, quats = tensor(scene.means), tensor(scene.quats)
    scales = tensor(np.exp(scene.log_scales))
    opacities = tensor(np.float32(1) / (np.float32(1) + np.exp(-scene.opacities)))
    colours = tensor(scene.sh)
    sh_degree = scene.sh_degree

    def render(q):
        cam = q.camera
        if q.subset is None:
            m, r, s, o, c = means, quats, scales, opacities, colours
        else:
            idx = tensor(q.subset)
            m, r, s, o, c = means[idx], quats[idx], scales[idx], opacities[idx], colours[idx]
            if q.log_scales is not None:  # a segmentation's refined scales, aligned with subset
                s = tensor(np.exp(q.log_scales))
        out_colours, out_alphas, _ = rasterization(
            means=m, quats=r, scales=s, opacities=o, colors=c,
            viewmats=tensor(cam.world_to_camera)[None], Ks=tensor(cam.K)[None],
            width=cam.width, height=cam.height, sh_degree=sh_degree,
            render_mode="RGB+D" if q.want_depth else "RGB")
        img = _numpy(out_colours[0]).astype(np.float32)  # (H, W, 3) or (H, W, 4)
        alpha = _numpy(out_alphas[0])[..., 0].astype(np.float32)
        rgb = img[..., :3]
        if np.any(q.background):  # gsplat composites on black
            rgb = rgb + (1.0 - alpha)[..., None] * q.background
        out = {"rgb": rgb, "alpha": alpha}
        if q.want_depth:
            out["depth"] = img[..., 3]
        return out
    return render


def _save_jpeg(path, image):
    from PIL import Image
    Image.fromarray(image).save(path, quality=95)


def sam2_segmenter(predictor, torch=None, save_jpeg=_save_jpeg, autocast=True):
    """A vcar segmenter on a SAM 2 video predictor (sam2.build_sam.build_sam2_video_predictor).

    The frames of the request are a video: written as JPEGs named by index (SAM 2's loader
    reads those), the prompt's points/box added on frame 0, masks propagated forward; a frame
    SAM 2 says nothing about gets None ("no evidence"). Text prompts need a grounding model
    first (make a box)."""
    if torch is None:
        import torch

    def segment(request):
        p = request.prompt
        points = p["points"] if len(p["points"]) else None
        labels = p["point_labels"] if len(p["points"]) else None
        if points is None and p["box"] is None:
            raise ValueError("SAM 2 needs points or a box on the reference view")
        video = tempfile.mkdtemp(prefix="vcar-sam2-")
        try:
            for k in range(len(request)):
                save_jpeg(os.path.join(video, "%05d.jpg" % k), request.image(k))
            masks = [None] * len(request)
            with contextlib.ExitStack() as ctx:
                ctx.enter_context(torch.inference_mode())
                if autocast:
                    ctx.enter_context(torch.autocast("cuda", dtype=torch.bfloat16))
                state = predictor.init_state(video_path=video)
                predictor.add_new_points_or_box(inference_state=state, frame_idx=0, obj_id=1, points=points,
                                                labels=labels, box=p["box"])
                for frame, obj_ids, logits in predictor.propagate_in_video(state):
                    k = list(obj_ids).index(1)
                    masks[frame] = _numpy(logits[k] > 0.0).reshape(request.cameras[frame].height,
                                                                     request.cameras[frame].width)
            return masks
        finally:
            shutil.rmtree(video, ignore_errors=True)
    return segment


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True, help="a trained 3DGS scene (PLY, SPZ, .splat)")
    ap.add_argument("--cameras", required=True, help="COLMAP sparse/0, cameras.json or transforms.json")
    ap.add_argument("--view", default="0", help="the prompt view: camera name or index")
    ap.add_argument("--point", action="append", required=True, help="u,v pixel on the prompt view (repeat)")
    ap.add_argument("--sam2-config", required=True)
    ap.add_argument("--sam2-checkpoint", required=True)
    ap.add_argument("--device", default="cuda")
    ap.add_argument("--preset", default=vcar.DEFAULT_PRESET, choices=vcar.PRESETS)
    ap.add_argument("--out", default="object.ply")
    a = ap.parse_args(argv)

    from sam2.build_sam import build_sam2_video_predictor

    scene = vcar.read_scene(a.scene)
    cameras = vcar.read_cameras(a.cameras)
    view = int(a.view) if a.view.isdigit() else a.view
    points = [[float(x) for x in p.split(",")] for p in a.point]
    predictor = build_sam2_video_predictor(a.sam2_config, a.sam2_checkpoint, device=a.device)

    def progress(p):
        print("\r%-24s %4d/%-4d %6.1f s" % (p.stage, p.view, p.views, p.elapsed_s), end="", flush=True)

    result = vcar.segment(scene, cameras, {"reference_view": view, "points": points},
                          sam2_segmenter(predictor, autocast=a.device.startswith("cuda")),
                          renderer=gsplat_renderer(scene, a.device),
                          params=a.preset, progress=progress)
    print()
    vcar.write_ply(a.out, scene, result["indices"], result["log_scales"])
    d = result["diagnostics"]
    print("%d of %d Gaussians -> %s (view completeness %.0f deg, SSS %s)" % (
        len(result["indices"]), len(scene), a.out, d["max_gap_deg"], "yes" if d["sss_triggered"] else "no"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
