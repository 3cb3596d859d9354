"""vcar.Scene: values read from PLY against an independent numpy parse, arrays that are views
(no copies), scenes from numpy arrays, and clear errors for wrong shapes, dtypes and NaN."""
import gc
import os

import numpy as np
import pytest

import vcar
from conftest import DATA_DIR

TRAIN = os.path.join(DATA_DIR, "train-1000.ply")  # SH degree 3 and normals (extras)
DONUT = os.path.join(DATA_DIR, "donut.ply")


def parse_ply(path):
    """An independent reader for these fixtures (binary little-endian, float properties only)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    n = int(next(line for line in header if line.startswith("element vertex")).split()[2])
    names = [line.split()[2] for line in header if line.startswith("property float")]
    return np.frombuffer(data, dtype=[(name, "<f4") for name in names], count=n, offset=end)


def columns(rows, *names):
    return np.stack([rows[n] for n in names], axis=1)


def small_arrays(n=5):
    rng = np.random.default_rng(1)
    means = rng.normal(size=(n, 3)).astype(np.float32)
    quats = np.tile(np.array([1, 0, 0, 0], np.float32), (n, 1))
    log_scales = np.full((n, 3), -3, np.float32)
    opacities = np.full(n, 2, np.float32)
    return means, quats, log_scales, opacities


# ---- reading ------------------------------------------------------------------------------------

def test_read_ply_matches_an_independent_parse():
    s = vcar.read_ply(TRAIN)
    rows = parse_ply(TRAIN)
    assert len(s) == len(rows) == 1000 and s.sh_degree == 3
    for arr, shape in ((s.means, (1000, 3)), (s.quats, (1000, 4)), (s.log_scales, (1000, 3)), (s.opacities, (1000,)),
                       (s.sh, (1000, 16, 3))):
        assert arr.dtype == np.float32 and arr.shape == shape
    np.testing.assert_array_equal(s.means, columns(rows, "x", "y", "z"))
    np.testing.assert_array_equal(s.quats, columns(rows, "rot_0", "rot_1", "rot_2", "rot_3"))  # w, x, y, z
    np.testing.assert_array_equal(s.log_scales, columns(rows, "scale_0", "scale_1", "scale_2"))
    np.testing.assert_array_equal(s.opacities, rows["opacity"])
    np.testing.assert_array_equal(s.sh[:, 0, :], columns(rows, "f_dc_0", "f_dc_1", "f_dc_2"))
    # f_rest is channel-major in the file: f_rest_{c * 15 + k - 1} is coefficient k of channel c.
    for c in range(3):
        for k in range(1, 16):
            np.testing.assert_array_equal(s.sh[:, k, c], rows["f_rest_%d" % (c * 15 + k - 1)])
    assert s.extra_names == ["nx", "ny", "nz"]
    np.testing.assert_array_equal(s.extra, columns(rows, "nx", "ny", "nz"))


def test_read_errors_name_the_file(tmp_path):
    with pytest.raises(vcar.Error, match="missing.ply"):
        vcar.read_ply(tmp_path / "missing.ply")
    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\nend_header\n")
    with pytest.raises(vcar.Error, match="bad.ply") as e:
        vcar.read_ply(bad)
    assert isinstance(e.value, ValueError) and "bad.ply" in e.value.where


# ---- views, not copies --------------------------------------------------------------------------

def test_arrays_are_views_of_the_scene():
    s = vcar.read_ply(DONUT)
    assert s.means is s.means and s.quats is s.quats and s.log_scales is s.log_scales
    for name in ("opacities", "sh"):
        a, b = getattr(s, name), getattr(s, name)
        assert not a.flags.owndata and a.flags.writeable, name
        assert np.shares_memory(a, b), name  # two accesses, one buffer
    t = vcar.read_ply(TRAIN)
    assert not t.extra.flags.owndata and np.shares_memory(t.extra, t.extra)
    v = s.opacities
    del s
    gc.collect()
    assert np.isfinite(v).all()  # the view keeps its scene alive


def test_writes_reach_the_library():
    s = vcar.read_ply(DONUT)
    cam = vcar.Camera.look_at(s.means.mean(0) + np.array([0, 0, 3], np.float32), s.means.mean(0), [0, 1, 0],
                              [[100, 0, 64], [0, 100, 48], [0, 0, 1]], 128, 96)
    before = vcar.render(s, cam)
    s.sh[:, 0, :] = vcar.rgb_to_sh(np.tile([1, 0, 0], (len(s), 1)))[:, 0, :]  # every splat red, in place
    if s.sh_degree:
        s.sh[:, 1:, :] = 0
    red = vcar.render(s, cam)
    covered = red["alpha"] > 0.5
    assert covered.any()
    assert (red["rgb"][covered][:, 1:] < 1e-3).all() and (red["rgb"][covered][:, 0] > 0.4).all()
    assert not np.array_equal(before["rgb"], red["rgb"])
    s.opacities[:] = -30.0  # invisible
    assert vcar.render(s, cam)["alpha"].max() == 0.0
    s.means += np.float32(100.0)  # the numpy storage itself: the next C++ call sees it
    np.testing.assert_array_equal(s.subset([0, 1]).means, s.means[:2])


def test_scene_from_numpy_keeps_the_geometry_arrays():
    means, quats, log_scales, opacities = small_arrays()
    sh = vcar.rgb_to_sh(np.full((5, 3), 0.25))
    s = vcar.Scene(means, quats, log_scales, opacities, sh=sh)
    assert np.shares_memory(s.means, means) and np.shares_memory(s.quats, quats)
    assert np.shares_memory(s.log_scales, log_scales)
    assert not np.shares_memory(s.opacities, opacities) and not np.shares_memory(s.sh, sh)  # copied once
    np.testing.assert_array_equal(s.opacities, opacities)
    np.testing.assert_array_equal(s.sh, sh)
    strided = np.asfortranarray(means)  # not C-contiguous: copied
    s2 = vcar.Scene(strided, quats, log_scales, opacities)
    assert not np.shares_memory(s2.means, strided) and s2.sh.shape == (5, 1, 3) and s2.sh_degree == 0
    np.testing.assert_array_equal(s2.means, means)


def test_subset_copy_and_round_trip(tmp_path):
    s = vcar.read_ply(TRAIN)
    sub = s.subset([5, 2, 999])
    np.testing.assert_array_equal(sub.means, s.means[[5, 2, 999]])
    np.testing.assert_array_equal(sub.sh, s.sh[[5, 2, 999]])
    np.testing.assert_array_equal(sub.extra, s.extra[[5, 2, 999]])
    c = s.copy()
    c.means[:] = 0
    assert not np.array_equal(s.means, c.means)

    vcar.write_ply(tmp_path / "all.ply", s)
    back = vcar.read_ply(tmp_path / "all.ply")
    for name in ("means", "quats", "log_scales", "opacities", "sh", "extra"):
        np.testing.assert_array_equal(getattr(back, name), getattr(s, name), name)
    refined = s.log_scales[[3, 7]] - np.float32(1.0)
    vcar.write_ply(tmp_path / "sel.ply", s, np.array([3, 7]), refined)
    sel = vcar.read_ply(tmp_path / "sel.ply")
    np.testing.assert_array_equal(sel.means, s.means[[3, 7]])
    np.testing.assert_array_equal(sel.log_scales, refined)

    vcar.write_scene(tmp_path / "s.splat", s)  # .splat keeps positions as float32
    np.testing.assert_array_equal(vcar.read_scene(tmp_path / "s.splat").means, s.means)


def test_render_subset_and_depth():
    s = vcar.read_ply(DONUT)
    c = s.means.mean(0)
    cam = vcar.Camera.look_at(c + np.array([0, -3, 0.5], np.float32), c, [0, 0, 1],
                              [[80, 0, 40], [0, 80, 30], [0, 0, 1]], 80, 60, "v")
    full = vcar.render(s, cam, depth=True)
    assert full["rgb"].shape == (60, 80, 3) and full["alpha"].shape == (60, 80) and full["depth"].shape == (60, 80)
    assert vcar.render(s, cam)["depth"] is None
    none = vcar.render(s, cam, subset=np.array([], np.int64))
    assert none["alpha"].max() == 0.0
    white = vcar.render(s, cam, subset=[], background=(1, 1, 1))
    assert (white["rgb"] == 1.0).all()
    with pytest.raises(vcar.Error, match=r"subset: \[0\] = 45624 is out of range"):
        vcar.render(s, cam, subset=[len(s)])
    with pytest.raises(vcar.Error, match="subset: must hold integers, got float64"):
        vcar.render(s, cam, subset=np.array([1.0]))


def test_images_and_masks(tmp_path):
    m = np.zeros((7, 9), bool)
    m[2:5, 3:8] = True
    vcar.write_png(tmp_path / "m.png", m)
    back = vcar.read_mask(tmp_path / "m.png")
    assert back.dtype == np.bool_ and back.shape == (7, 9)
    np.testing.assert_array_equal(back, m)
    img = np.arange(7 * 9 * 3, dtype=np.uint8).reshape(7, 9, 3)
    vcar.write_png(tmp_path / "i.png", img)
    np.testing.assert_array_equal(vcar.read_image(tmp_path / "i.png"), img)


# ---- errors -------------------------------------------------------------------------------------

def test_wrong_dtypes_shapes_and_values():
    means, quats, log_scales, opacities = small_arrays()
    with pytest.raises(vcar.Error, match=r"means: must be float32, got float64 \(convert with .astype") as e:
        vcar.Scene(means.astype(np.float64), quats, log_scales, opacities)
    assert e.value.where == "means" and isinstance(e.value, ValueError)
    with pytest.raises(vcar.Error, match=r"quats: must have shape \(5, 4\), got \(5, 3\)"):
        vcar.Scene(means, quats[:, :3].copy(), log_scales, opacities)
    with pytest.raises(vcar.Error, match=r"means: must have shape \(N, 3\), got \(5,\)"):
        vcar.Scene(means[:, 0].copy(), quats, log_scales, opacities)
    with pytest.raises(vcar.Error, match=r"opacities: must have shape \(5,\), got \(4,\)"):
        vcar.Scene(means, quats, log_scales, opacities[:4])
    with pytest.raises(vcar.Error, match="opacities: must be float32, got int64"):
        vcar.Scene(means, quats, log_scales, np.zeros(5, np.int64))
    bad = means.copy()
    bad[3, 1] = np.nan
    with pytest.raises(vcar.Error, match="means: row 3 holds a NaN or infinite value"):
        vcar.Scene(bad, quats, log_scales, opacities)
    bad = log_scales.copy()
    bad[4, 0] = np.inf
    with pytest.raises(vcar.Error, match="log_scales: row 4 holds a NaN"):
        vcar.Scene(means, quats, bad, opacities)
    bad = quats.copy()
    bad[2] = 0
    with pytest.raises(vcar.Error, match="quats: row 2 is a zero quaternion"):
        vcar.Scene(means, bad, log_scales, opacities)
    with pytest.raises(vcar.Error, match="K = 1, 4, 9 or 16"):
        vcar.Scene(means, quats, log_scales, opacities, sh=np.zeros((5, 5, 3), np.float32))
    sh = np.zeros((5, 4, 3), np.float32)
    sh[1, 2, 0] = np.nan
    with pytest.raises(vcar.Error, match="sh: row 1 holds a NaN"):
        vcar.Scene(means, quats, log_scales, opacities, sh=sh)
    with pytest.raises(vcar.Error, match=r"extra: must have shape \(5, 2\)"):
        vcar.Scene(means, quats, log_scales, opacities, extra=np.zeros((5, 1), np.float32), extra_names=["a", "b"])


def test_setters_and_late_nan():
    s = vcar.Scene(*small_arrays())
    with pytest.raises(vcar.Error, match="means: must be float32, got float64"):
        s.means = np.zeros((5, 3))
    with pytest.raises(vcar.Error, match=r"means: must have shape \(5, 3\)"):
        s.means = np.zeros((6, 3), np.float32)
    with pytest.raises(vcar.Error, match=r"sh: must have shape \(5, 1, 3\)"):
        s.sh = np.zeros((5, 4, 3), np.float32)
    s.means = np.ones((5, 3), np.float32)
    np.testing.assert_array_equal(s.subset([4]).means, [[1, 1, 1]])
    s.means[2, 0] = np.nan  # in place, after construction: caught when a call uses the scene
    cam = vcar.Camera.look_at([0, 0, 5], [0, 0, 0], [0, 1, 0], np.diag([50.0, 50.0, 1.0]), 32, 32)
    with pytest.raises(vcar.Error, match="scene: Gaussian 2 has a NaN or infinite value"):
        vcar.render(s, cam)
    with pytest.raises(vcar.Error, match="Gaussian 2"):
        s.validate()
