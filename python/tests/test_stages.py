"""The stages on their own: voting (Eq. 1-3) and the view-completeness geometry (Eq. 4-6, A.1-A.3)
against numpy brute force, the spiral (Eq. 7-8) against its definition, and voting + ABR composed
by hand giving exactly what vcar.segment gives."""
import numpy as np
import pytest

import vcar


def scene_of(means):
    n = len(means)
    return vcar.Scene(np.ascontiguousarray(means, dtype=np.float32), np.tile(np.float32([1, 0, 0, 0]), (n, 1)),
                      np.full((n, 3), -4, np.float32), np.zeros(n, np.float32))


def test_voting_against_brute_force():
    rng = np.random.default_rng(7)
    n, f = 600, 100.0
    # Means built so that, with the cameras below (identity pose, principal points shifted by whole
    # pixels), each projects to a pixel centre: the containing pixel is never in doubt.
    j = rng.integers(-6, 72, n)
    i = rng.integers(-6, 56, n)
    z = rng.uniform(1, 5, n) * np.where(rng.random(n) < 0.1, -1, 1)  # some behind the cameras
    means = np.stack([(j + 0.5 - 32) * z / f, (i + 0.5 - 24) * z / f, z], 1)
    scene = scene_of(means)
    cams = [(0, 0, 64, 48), (7, -3, 50, 40), (-5, 4, 70, 30)]  # (shift u, shift v, W, H)
    masks = [rng.random((h, w)) < 0.5 for (_, _, w, h) in cams]
    masks[1] = None  # no evidence from this view
    voting = vcar.VisibilityVoting(scene)
    F, V = np.zeros(n, int), np.zeros(n, int)
    for (du, dv, w, h), m in zip(cams, masks):
        K = [[f, 0, 32 + du], [0, f, 24 + dv], [0, 0, 1]]
        voting.add_view(vcar.Camera(K, np.eye(4), w, h), m)
        if m is None:
            continue
        u, v = j + du, i + dv  # the containing pixel
        vis = (z > 0) & (u >= 0) & (u < w) & (v >= 0) & (v < h)  # Eq. 1
        V += vis
        F += vis & m[np.clip(v, 0, h - 1), np.clip(u, 0, w - 1)]  # Eq. 2
    assert voting.views == 2 and len(voting) == n
    np.testing.assert_array_equal(voting.visible(), V)
    np.testing.assert_array_equal(voting.foreground(), F)
    R = np.float32(F) / np.float32(np.maximum(V, 1))  # Eq. 3
    np.testing.assert_array_equal(voting.ratios(), R)
    np.testing.assert_array_equal(voting.selected(0.5), np.nonzero(R >= 0.5)[0])

    cand = np.array([590, 3, 77, 10])
    sub = vcar.VisibilityVoting(scene, cand)
    for (du, dv, w, h), m in zip(cams, masks):
        sub.add_view(vcar.Camera([[f, 0, 32 + du], [0, f, 24 + dv], [0, 0, 1]], np.eye(4), w, h), m)
    np.testing.assert_array_equal(sub.candidates, cand)
    np.testing.assert_array_equal(sub.ratios(), R[cand])
    np.testing.assert_array_equal(sub.selected(0.5), np.sort(cand[R[cand] >= 0.5]))

    with pytest.raises(vcar.Error, match=r"mask: is 10x10 \(W x H\), the view is 64x48"):
        voting.add_view(vcar.Camera([[f, 0, 32], [0, f, 24], [0, 0, 1]], np.eye(4), 64, 48), np.zeros((10, 10), bool))


def test_robust_sphere_against_numpy():
    rng = np.random.default_rng(3)
    means = np.concatenate([rng.normal([1, 2, 3], 0.1, (300, 3)), [[40.0, 0, 0]]])  # one far outlier
    scene = scene_of(means)
    idx = np.arange(len(means))
    ref = np.array([1.0, 2.0, 8.0])
    got = vcar.robust_sphere(scene, idx, ref, eta=1.2)
    mu = scene.means.astype(np.float64)
    d = np.linalg.norm(mu - mu.mean(0), axis=1)  # Eq. 4
    inl = d <= d.mean() + 3 * d.std()
    c = mu[inl].mean(0)
    assert got["inliers"] == inl.sum() == 300
    np.testing.assert_allclose(got["center"], c, atol=1e-5)
    assert got["radius"] == pytest.approx(1.2 * np.linalg.norm(ref - c), rel=1e-5)  # Eq. 5


def test_lattice_and_gap_against_numpy():
    K = 500
    t = vcar.fibonacci_lattice(K)
    i = np.arange(K)
    phi, theta = np.arccos(1 - 2 * (i + 0.5) / K), np.pi * (1 + np.sqrt(5)) * i  # A.3
    np.testing.assert_allclose(t, np.stack([np.sin(phi) * np.cos(theta), np.sin(phi) * np.sin(theta), np.cos(phi)], 1),
                               atol=1e-6)
    rng = np.random.default_rng(5)
    pos = rng.normal(size=(12, 3)) + [0, 0, 3]  # cameras mostly above
    h = vcar.headings([0, 0, 0], pos)
    np.testing.assert_allclose(h, pos / np.linalg.norm(pos, axis=1, keepdims=True), atol=1e-6)
    g = vcar.max_angular_gap(t, h)
    best = (t.astype(np.float64) @ h.astype(np.float64).T).max(1)  # Eq. 6
    assert g["probe"] == int(np.argmin(best))
    assert g["Delta_max_deg"] == pytest.approx(np.degrees(np.arccos(best.min())), abs=1e-3)
    np.testing.assert_array_equal(g["direction"], t[g["probe"]])
    assert vcar.max_angular_gap(t, np.zeros((0, 3)))["Delta_max_deg"] == 180.0


def test_view_completeness_and_valid_cameras():
    scene = scene_of(np.random.default_rng(0).normal(0, 0.05, (200, 3)))
    idx = np.arange(200)
    K = [[100, 0, 50], [0, 100, 50], [0, 0, 1]]
    ring = [vcar.Camera.look_at([3 * np.cos(a), 3 * np.sin(a), 0.5 * (-1) ** k], [0, 0, 0], [0, 0, 1], K, 100, 100,
                                "r%d" % k)
            for k, a in enumerate(np.linspace(0, 2 * np.pi, 12, endpoint=False))]
    away = vcar.Camera.look_at([0, 0, 3], [0, 0, 6], [0, 1, 0], K, 100, 100, "away")
    np.testing.assert_array_equal(vcar.valid_cameras(scene, idx, ring + [away]), np.arange(12))
    assert vcar.visible_fraction(scene, idx, away) == 0.0 and vcar.visible_fraction(scene, idx, ring[0]) == 1.0
    full = vcar.view_completeness(scene, idx, ring, [0, 0, 0], K=2000)
    front = vcar.view_completeness(scene, idx, ring[:3], [0, 0, 0], K=2000)
    assert front["Delta_max_deg"] > 90 > full["Delta_max_deg"]
    expect = vcar.max_angular_gap(vcar.fibonacci_lattice(2000), vcar.headings([0, 0, 0], [c.position for c in ring[:3]]))
    assert front["Delta_max_deg"] == expect["Delta_max_deg"] and front["probe"] == expect["probe"]
    np.testing.assert_array_equal(front["valid"], [0, 1, 2])


def test_spiral_follows_eq_7_8():
    ref = vcar.Camera.look_at([0, -4, 1], [0, 0, 0], [0, 0, 1], [[100, 0, 50], [0, 100, 40], [0, 0, 1]], 100, 80, "ref")
    up = vcar.estimate_scene_up([ref])
    np.testing.assert_allclose(up, ref.up, atol=1e-6)
    c, r = np.array([0.5, 0.2, 0.1]), 2.0
    params = {"preset": "nvos", "S1": 2, "S2": 5, "phi_s_deg": -30, "phi_e_deg": 45}
    cams = vcar.spiral_cameras(c, r, up, ref, params)
    assert [x.name for x in cams] == ["sss_%03d" % k for k in range(10)]
    N = 10
    for k, cam in enumerate(cams):
        d = cam.position - c
        assert np.linalg.norm(d) == pytest.approx(r, rel=1e-5)  # Eq. 8: on the sphere
        phi = np.degrees(np.arcsin(np.dot(d / r, up / np.linalg.norm(up))))
        assert phi == pytest.approx(-30 + 75 * k / (N - 1), abs=1e-3)  # Eq. 7: elevation
        np.testing.assert_allclose(cam.project([c])[0, :2], [50, 40], atol=1e-3)  # looks at the centre
        assert (cam.width, cam.height, cam.fx) == (100, 80, 100.0)  # the reference view's intrinsics
    gap = vcar.gap_directed_cameras(c, r, up, [1, 0, 0], ref, {"gap_directed_views": 4})
    assert len(gap) == 4 and gap[0].name == "sss_gap_000"
    np.testing.assert_allclose((gap[0].position - c) / r, [1, 0, 0], atol=1e-5)  # the first on the gap axis


def test_abr_flags_an_overflowing_needle():
    means = np.array([[0, 0, 0], [0.3, 0, 0]], np.float32)
    s = vcar.Scene(means, np.tile(np.float32([1, 0, 0, 0]), (2, 1)),
                   np.log(np.array([[0.3, 0.005, 0.005], [0.01, 0.01, 0.01]], np.float32)), np.full(2, 5, np.float32))
    cam = vcar.Camera.look_at([0, 0, 3], [0, 0, 0], [0, 1, 0], [[200, 0, 100], [0, 200, 100], [0, 0, 1]], 200, 200)
    mask = np.zeros((200, 200), bool)
    uv = cam.project(means)
    for (u, v, _) in uv:  # discs of 6 px around each centre: the needle (1 sigma = 20 px) overflows
        yy, xx = np.mgrid[0:200, 0:200]
        mask |= (xx + 0.5 - u) ** 2 + (yy + 0.5 - v) ** 2 < 36
    abr = vcar.BoundaryRefinement(s, [0, 1], params="nvos")
    abr.add_view(cam, mask)
    out = abr.finish()
    np.testing.assert_array_equal(abr.n_vis(), [1, 1])
    np.testing.assert_array_equal(abr.n_ovf(), [1, 0])
    assert out["flagged"] == 1 and out["compressed"] == 1 and out["axis_compressed"].tolist() == [1, 0]
    assert out["log_scales"][0, 0] < s.log_scales[0, 0]  # the dominant axis shrinks ...
    np.testing.assert_array_equal(out["log_scales"][0, 1:], s.log_scales[0, 1:])  # ... and only it
    np.testing.assert_array_equal(out["log_scales"][1], s.log_scales[1])


def test_stages_compose_to_the_pipeline(world, rig):
    """Coarse voting then ABR on the training masks, by hand, is vcar.segment without SSS."""
    oracle = vcar.synth.OracleSegmenter(world)
    masks = [oracle.mask(cam, k) for k, cam in enumerate(rig.train)]
    voting = vcar.VisibilityVoting(world.scene)
    for cam, m in zip(rig.train, masks):
        voting.add_view(cam, m)
    selected = voting.selected(0.5)  # nvos tau_coarse
    abr = vcar.BoundaryRefinement(world.scene, selected, params="nvos")
    for cam, m in zip(rig.train, masks):
        abr.add_view(cam, m)
    refined = abr.finish()
    r = vcar.segment(world.scene, rig.train, {"reference_view": rig.reference}, oracle,
                     params={"preset": "nvos", "enable_sss": False})
    assert len(selected) > 0 and refined["compressed"] > 0
    np.testing.assert_array_equal(r["indices"], selected)
    np.testing.assert_array_equal(r["scores"], voting.ratios()[selected])
    np.testing.assert_array_equal(r["log_scales"], refined["log_scales"])
    assert r["diagnostics"]["abr_compressed"] == refined["compressed"]
