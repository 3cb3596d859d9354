#!/usr/bin/python3
"""Segments the target of a synthetic world with a segmenter written in numpy, and evaluates it.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/segment_synthetic.py [--out DIR]

The world (vcar.synth) has exact ground truth: which Gaussians belong to the target and its
silhouette in any view. The segmenter is ten lines of numpy: it picks the colour of the
reference frame under the first prompt point and marks, in every frame vcar hands it, the
pixels within `tol` of that colour (the synthetic target has its own colour). vcar.segment
runs VCAR with it; vcar.eval scores the selection on held-out views as `vcar eval` does, beside
the same run with the oracle segmenter (exact masks). With --out, writes the object as a PLY
and renders of the scene and of the object from the first held-out view.
Runs in seconds on a CPU (docs/python.md).
"""
import argparse
import os
import sys

import numpy as np

import vcar


def colour_picker(tol=0.08, radius=6):
    """A segmenter: request -> one bool (H, W) mask per frame. Its palette is the colours of the
    prompt view in a (2 radius + 1)^2 window around the first prompt point (the target is
    textured); a pixel is foreground when a palette colour is within about `tol` of it in every
    channel (colours quantised to 32 levels a channel, one table lookup a pixel)."""
    step = 8
    reach = max(1, round(tol * 255 / step))

    def segment(request):
        frame0 = request.image(0)  # (H, W, 3) uint8, rendered on demand: frame 0 is the prompt view
        u, v = (int(x) for x in request.prompt["points"][0])
        window = frame0[max(0, v - radius):v + radius + 1, max(0, u - radius):u + radius + 1]
        table = np.zeros((256 // step,) * 3, bool)
        for r, g, b in np.unique(window.reshape(-1, 3) // step, axis=0):
            table[max(0, r - reach):r + reach + 1, max(0, g - reach):g + reach + 1, max(0, b - reach):b + reach + 1] = True
        masks = []
        for k in range(len(request)):
            q = (frame0 if k == 0 else request.image(k)) // step
            masks.append(table[q[..., 0], q[..., 1], q[..., 2]])
        return masks
    return segment


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--gaussians", type=int, default=20000)
    ap.add_argument("--rig", default="forward", help="forward, orbit, sparse, hemisphere")
    ap.add_argument("--tol", type=float, default=0.08, help="colour tolerance of the numpy segmenter")
    ap.add_argument("--preset", default=vcar.DEFAULT_PRESET, choices=vcar.PRESETS)
    ap.add_argument("--out", help="folder for object.ply and renders")
    a = ap.parse_args(argv)

    world = vcar.synth.generate_world(seed=a.seed, n_gaussians=a.gaussians)
    rig = vcar.synth.make_rig(a.rig, world, width=320, height=240, seed=a.seed)
    reference = rig.train[rig.reference]
    # One positive point deep inside the target's visible part of the reference view.
    prompt = vcar.synth.prompt_points(world.visible_mask(reference), rig.reference, n_points=1)
    print("%s; %d training views, prompt (%.1f, %.1f) on '%s'" % (
        world, len(rig.train), prompt["points"][0][0], prompt["points"][0][1], reference.name))

    truth = world.gaussians_of(world.target_id)
    rows = []
    for name, segmenter in (("numpy colour picker", colour_picker(a.tol)),
                            ("oracle (exact masks)", vcar.synth.OracleSegmenter(world))):
        result = vcar.segment(world.scene, rig.train, prompt, segmenter, params=a.preset)
        metrics = vcar.eval.evaluate_selection(
            world.scene, result["indices"], rig.eval, lambda k: world.silhouette_mask(rig.eval[k]), truth,
            log_scales=result["log_scales"])
        d = result["diagnostics"]
        rows.append((name, result, metrics))
        print("%-22s %6d Gaussians (%d true)  mIoU %.3f  boundary F1 %.3f  3D F1 %.3f  SSS %s  %.2f s" % (
            name, metrics["selected"], metrics["true"], metrics["mIoU"], metrics["boundary_f1"], metrics["f1_3d"],
            "yes" if d["sss_triggered"] else "no", d["timings_s"]["total"]))

    if a.out:
        os.makedirs(a.out, exist_ok=True)
        result = rows[0][1]
        vcar.write_ply(os.path.join(a.out, "object.ply"), world.scene, result["indices"], result["log_scales"])
        view = rig.eval[0]
        vcar.write_png(os.path.join(a.out, "scene.png"), vcar.render(world.scene, view)["rgb"])
        obj = vcar.render(world.scene, view, subset=result["indices"], log_scales=result["log_scales"],
                          background=(1, 1, 1))
        vcar.write_png(os.path.join(a.out, "object.png"), obj["rgb"])
        print("wrote", os.path.join(a.out, "object.ply"), "and renders of", view.name)
    return 0 if rows[0][2]["mIoU"] > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
