"""The metrics of conventions §6 (vcar::eval), and the evaluation protocol of `vcar eval`."""
import os

from ._vcar import read_mask as _read_mask
from ._vcar import render as _render
from ._vcar.eval import (  # noqa: F401
    ALPHA_DEFAULT,
    ALPHA_RELEASED,
    band_width,
    evaluate_mask,
    predicted_mask,
    selection_scores,
    weighted_selection_scores,
)

_METRICS = ("iou", "accuracy", "boundary_iou", "boundary_f1", "trimap_iou")


def evaluate_selection(scene, indices, views, gt_masks, true_ids, log_scales=None, alpha=ALPHA_DEFAULT):
    """Scores a selection as `vcar eval --json` does (conventions §6).

    Renders the selected Gaussians (with `log_scales` (M, 3) when given, e.g. the refined scales of
    a segmentation) from each held-out camera in `views`, thresholds alpha > `alpha`, compares with
    `gt_masks[k]` (a bool/uint8 (H, W) array, or a callable k -> mask), and scores the selected
    indices against `true_ids`. Returns mIoU, mAcc, boundary_iou, boundary_f1, trimap_iou (means
    over the views), precision_3d, recall_3d, f1_3d and their opacity-area weighted variants,
    selected, true, alpha and the per-view metrics in "views".
    """
    per_view = []
    for k, cam in enumerate(views):
        gt = gt_masks(k) if callable(gt_masks) else gt_masks[k]
        out = _render(scene, cam, subset=indices, log_scales=log_scales)
        m = evaluate_mask(predicted_mask(out["alpha"], alpha), gt)
        m["view"] = cam.name
        per_view.append(m)
    means = {}
    for key in _METRICS:  # summed in view order, then divided: the C++ mean's operations
        total = 0.0
        for m in per_view:
            total += m[key]
        means[key] = total / len(per_view) if per_view else 0.0
    s3 = selection_scores(indices, true_ids, len(scene))
    w3 = weighted_selection_scores(indices, true_ids, scene)
    return {
        "mIoU": means["iou"], "mAcc": means["accuracy"], "boundary_iou": means["boundary_iou"],
        "boundary_f1": means["boundary_f1"], "trimap_iou": means["trimap_iou"],
        "precision_3d": s3["precision"], "recall_3d": s3["recall"], "f1_3d": s3["f1"],
        "precision_3d_weighted": w3["precision"], "recall_3d_weighted": w3["recall"],
        "f1_3d_weighted": w3["f1"], "selected": len(indices), "true": len(true_ids),
        "alpha": alpha, "views": per_view,
    }


def evaluate_on_dataset(folder, indices, log_scales=None, alpha=ALPHA_DEFAULT, scene=None):
    """evaluate_selection on a synthetic dataset folder (`vcar synth`, synth.export_dataset): its
    held-out views, their ground-truth silhouettes (gt/silhouettes) and the target's true ids.
    `scene` defaults to the dataset's own scene.ply."""
    from . import synth

    world = synth.load_world(folder)
    rig = synth.load_rig(folder)
    if scene is None:
        scene = world.scene

    def gt(k):
        return _read_mask(os.path.join(folder, "gt", "silhouettes", rig.eval[k].name + ".png"))

    return evaluate_selection(scene, indices, rig.eval, gt, world.gaussians_of(world.target_id),
                              log_scales=log_scales, alpha=alpha)
