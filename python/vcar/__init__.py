"""vcar: training-free segmentation of 3D Gaussian Splatting scenes (VCAR) from Python.

    import vcar
    scene = vcar.read_ply("point_cloud.ply")           # arrays are numpy views, no copies
    cameras = vcar.read_cameras("sparse/0")            # COLMAP, cameras.json, transforms.json
    result = vcar.segment(scene, cameras, {"reference_view": 0, "points": [[320, 240]]},
                          segmenter=my_sam)            # any callable: request -> masks
    vcar.write_ply("object.ply", scene, result["indices"], result["log_scales"])

The C++ library does the work (the GIL is released while it runs); see docs/python.md.
"""
from ._vcar import (  # noqa: F401
    DEFAULT_PRESET,
    PRESETS,
    BoundaryRefinement,
    Camera,
    Cancelled,
    Error,
    MaskFolderSegmenter,
    Progress,
    RenderRequest,
    Reselection,
    Scene,
    SegmentationRequest,
    VisibilityVoting,
    estimate_scene_up,
    fibonacci_lattice,
    gap_directed_cameras,
    headings,
    max_angular_gap,
    max_threads,
    params,
    read_cameras,
    read_image,
    read_mask,
    read_ply,
    read_scene,
    render,
    robust_sphere,
    segment,
    segment_objects,
    set_num_threads,
    spiral_cameras,
    valid_cameras,
    view_completeness,
    visible_fraction,
    write_cameras_json,
    write_colmap_text,
    write_ply,
    write_png,
    write_scene,
    write_transforms_json,
)
from . import eval, synth  # noqa: F401,E402

__version__ = "@PROJECT_VERSION@"

SH_C0 = 0.28209479177387814  # the degree-0 SH basis constant (conventions §3)


def rgb_to_sh(rgb):
    """DC coefficients (N, 1, 3) float32 whose degree-0 colour is `rgb` (N, 3) in [0, 1]."""
    import numpy as np

    rgb = np.asarray(rgb, dtype=np.float32)
    return ((rgb - np.float32(0.5)) / np.float32(SH_C0)).reshape(-1, 1, 3).astype(np.float32)
