"""vcar.Reselection: masks set one view at a time, the selection equal to vcar.segment's with the
same masks (nvos preset, SSS off) after every edit, the incremental path taken, the default preset
(robust) equal to vcar.segment's too, bad input."""
import numpy as np
import pytest

import vcar


def segment_with_masks(scene, cams, params, held):
    """vcar.segment with held[k] as training view k's mask (reference view 0: frame k is view k)."""
    def segmenter(request):
        return [held[k] for k in range(len(request.cameras))]
    return vcar.segment(scene, cams, {"reference_view": 0}, segmenter, params=params)


def test_reselection_follows_edits_like_segment(world, rig):
    cams = rig.train
    masks = [world.visible_mask(c) for c in cams]
    params = ("nvos", {"enable_sss": False})

    def segment_with(held):
        return segment_with_masks(world.scene, cams, params, held)

    session = vcar.Reselection(world.scene, cams, params)
    assert session.views == len(cams) and session.masks == 0
    held = list(masks)
    for k, m in enumerate(held):
        session.set_mask(k, m)
    first = session.select()
    want = segment_with(held)
    np.testing.assert_array_equal(first["indices"], want["indices"])
    np.testing.assert_array_equal(first["log_scales"], want["log_scales"])
    assert len(first["indices"]) > 100
    assert not first["reselection"]["abr_incremental"]

    held[1] = masks[2]  # a wrong mask, then a cleared one
    session.set_mask(1, masks[2])
    held[3] = None
    session.set_mask(3, None)
    second = session.select()
    want = segment_with(held)
    np.testing.assert_array_equal(second["indices"], want["indices"])
    np.testing.assert_array_equal(second["scores"], want["scores"])
    np.testing.assert_array_equal(second["log_scales"], want["log_scales"])
    stats = second["reselection"]
    assert stats["abr_incremental"] and stats["views_changed"] == 2
    assert stats["carried"] + stats["fresh"] == len(second["indices"])
    assert session.masks == len(cams) - 1


def test_reselection_default_preset_equals_segment(world, rig):
    """The default (robust) reads each view's render: the session renders them once; its selection
    equals vcar.segment's with the same masks and SSS off, before and after an edit."""
    cams = rig.train
    held = [world.visible_mask(c) for c in cams]
    params = ("robust", {"enable_sss": False})

    def segment_with(masks):
        return segment_with_masks(world.scene, cams, params, masks)

    session = vcar.Reselection(world.scene, cams, params)
    for k, m in enumerate(held):
        session.set_mask(k, m)
    first = session.select()
    want = segment_with(held)
    np.testing.assert_array_equal(first["indices"], want["indices"])
    np.testing.assert_array_equal(first["log_scales"], want["log_scales"])
    held[2] = None
    session.set_mask(2, None)
    second = session.select()
    np.testing.assert_array_equal(second["indices"], segment_with(held)["indices"])
    default = vcar.Reselection(world.scene, cams)  # no params: robust, SSS reported only
    for k, m in enumerate(held):
        default.set_mask(k, m)
    np.testing.assert_array_equal(default.select()["indices"], second["indices"])


def test_reselection_copies_the_geometry(world, rig):
    """Edits of the scene's arrays after the session was made do not leak into it."""
    scene = vcar.Scene(world.scene.means.copy(), world.scene.quats.copy(), world.scene.log_scales.copy(),
                       world.scene.opacities.copy())
    session = vcar.Reselection(scene, rig.train)
    for k, c in enumerate(rig.train):
        session.set_mask(k, world.visible_mask(c))
    before = session.select()
    scene.means[:] += 100.0  # moves every Gaussian out of view
    vcar.render(scene, rig.train[0])  # the scene itself sees the edit
    session.set_incremental_abr(False)
    after = session.select()
    np.testing.assert_array_equal(before["indices"], after["indices"])
    np.testing.assert_array_equal(before["log_scales"], after["log_scales"])


def test_reselection_bad_input(world, rig):
    session = vcar.Reselection(world.scene, rig.train)
    c = rig.train[0]
    with pytest.raises(vcar.Error, match="out of range"):
        session.set_mask(len(rig.train), np.zeros((c.height, c.width), bool))
    with pytest.raises(vcar.Error):
        session.set_mask(0, np.zeros((c.height + 1, c.width), bool))
    with pytest.raises(vcar.Error, match="occlusion_aware"):
        vcar.Reselection(world.scene, rig.train, ("nvos", {"occlusion_aware": True}))
    with pytest.raises(vcar.Error):
        vcar.Reselection(world.scene, [])
    assert session.select()["diagnostics"]["note"] != ""
