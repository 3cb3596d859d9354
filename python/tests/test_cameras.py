"""vcar.Camera: K and world-to-camera (OpenCV axes), the OpenGL / nerfstudio helpers against the
transforms.json reader, projection against numpy, and the readers of every camera format."""
import json
import os

import numpy as np
import pytest

import vcar

K = np.array([[120.0, 0.0, 80.0], [0.0, 110.0, 60.0], [0.0, 0.0, 1.0]])


def rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    x = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * x + (1 - np.cos(angle)) * x @ x  # Rodrigues


def world_to_camera(R, t):
    W = np.eye(4)
    W[:3, :3], W[:3, 3] = R, t
    return W


def test_k_and_world_to_camera_round_trip():
    W = world_to_camera(rotation([1, 2, 3], 0.7), [0.1, -0.2, 3.0])
    c = vcar.Camera(K, W, 160, 120, "v")
    assert (c.width, c.height, c.name) == (160, 120, "v")
    assert (c.fx, c.fy, c.cx, c.cy) == (120.0, 110.0, 80.0, 60.0) == c.intrinsics
    np.testing.assert_array_equal(c.K, K.astype(np.float32))
    np.testing.assert_array_equal(c.world_to_camera, W.astype(np.float32))
    assert c.world_to_camera.dtype == np.float32
    np.testing.assert_allclose(c.camera_to_world, np.linalg.inv(W), atol=1e-6)
    np.testing.assert_allclose(c.position, -W[:3, :3].T @ W[:3, 3], atol=1e-6)
    assert vcar.Camera(c.K, c.world_to_camera, 160, 120, "v") == c  # exact
    assert vcar.Camera(K, W[:3], 160, 120, "v") == c  # (3, 4) accepted


def test_project_matches_numpy():
    W = world_to_camera(rotation([0, 1, 0], 0.3), [0.2, 0.1, 4.0])
    c = vcar.Camera(K, W, 160, 120)
    pts = np.random.default_rng(0).normal(size=(50, 3))
    cam = (W[:3, :3] @ pts.T).T + W[:3, 3]
    uv = (K @ cam.T).T
    got = c.project(pts)
    np.testing.assert_allclose(got[:, 0], uv[:, 0] / uv[:, 2], rtol=1e-4, atol=1e-3)
    np.testing.assert_allclose(got[:, 1], uv[:, 1] / uv[:, 2], rtol=1e-4, atol=1e-3)
    np.testing.assert_allclose(got[:, 2], cam[:, 2], rtol=1e-5, atol=1e-5)


def test_opengl_helpers_match_the_transforms_reader(tmp_path):
    rng = np.random.default_rng(2)
    cams = [vcar.Camera(K, world_to_camera(rotation(rng.normal(size=3), rng.uniform(0, 3)), rng.normal(size=3)),
                        160, 120, "f%d" % i) for i in range(4)]
    vcar.write_transforms_json(tmp_path / "transforms.json", cams)
    read = vcar.read_cameras(tmp_path / "transforms.json")
    with open(tmp_path / "transforms.json") as f:
        tj = json.load(f)
    for frame, r, c in zip(tj["frames"], read, cams):
        mine = vcar.Camera.from_nerfstudio(K, frame["transform_matrix"], tj["w"], tj["h"], frame["file_path"])
        assert mine == r  # the same conversion as io/transforms_json.hpp, bit for bit
        np.testing.assert_allclose(r.world_to_camera, c.world_to_camera, atol=1e-5)
        np.testing.assert_allclose(c.to_opengl(), np.array(frame["transform_matrix"]), atol=1e-6)
        back = vcar.Camera.from_opengl(c.K, c.to_opengl(), c.width, c.height, c.name)
        np.testing.assert_allclose(back.world_to_camera, c.world_to_camera, atol=1e-5)
    # OpenGL looks down -z: a point in front of an OpenGL camera has camera z > 0 in OpenCV axes.
    gl = np.eye(4)
    gl[:3, 3] = [0, 0, 5]
    c = vcar.Camera.from_opengl(K, gl, 160, 120)
    np.testing.assert_allclose(c.project([[0, 0, 0]]), [[80, 60, 5]])
    np.testing.assert_allclose(c.up, [0, 1, 0], atol=1e-7)
    cv = vcar.Camera.from_camera_to_world(K, gl @ np.diag([1, -1, -1, 1]), 160, 120)
    assert cv == c


def test_look_at():
    c = vcar.Camera.look_at([3, 1, 2], [0, 0, 0.5], [0, 0, 1], K, 160, 120, "l")
    np.testing.assert_allclose(c.project([[0, 0, 0.5]])[0, :2], [80, 60], atol=1e-4)
    assert c.up[2] > 0 and np.linalg.norm(c.forward) == pytest.approx(1, abs=1e-6)


def test_readers_agree(world, rig, tmp_path):
    vcar.synth.export_dataset(tmp_path, world, rig, render_images=False)
    cams = {fmt: vcar.read_cameras(tmp_path / path) for fmt, path in
            (("inria", "cameras.json"), ("nerfstudio", "transforms.json"), ("colmap", "sparse/0"), ("folder", "."))}
    for fmt, cs in cams.items():
        assert [c.name for c in cs] == [c.name for c in rig.train], fmt
        for a, b in zip(cs, rig.train):
            assert (a.width, a.height) == (b.width, b.height)
            np.testing.assert_allclose(a.world_to_camera, b.world_to_camera, atol=1e-5, err_msg=fmt)
            np.testing.assert_allclose(a.K, b.K, rtol=1e-6, err_msg=fmt)


@pytest.mark.parametrize("k, w, message", [
    ([[100, 1, 50], [0, 100, 40], [0, 0, 1]], np.eye(4), "has skew"),
    ([[100, 0, 50], [0, 100, 40], [0, 0, 2]], np.eye(4), r"must be \[\[fx, 0, cx\]"),
    ([[-100, 0, 50], [0, 100, 40], [0, 0, 1]], np.eye(4), "focal lengths"),
    ([[100, 0, 50], [0, 100, 40]], np.eye(4), r"K: must have shape \(3, 3\)"),
    ([[100, 0, np.nan], [0, 100, 40], [0, 0, 1]], np.eye(4), "NaN"),
    (K, np.diag([2.0, 1, 1, 1]), "not a rotation"),
    (K, np.diag([1.0, 1, -1, 1]), "not a rotation"),
    (K, np.ones((4, 4)), r"last row must be \[0, 0, 0, 1\]"),
    (K, np.eye(3), r"world_to_camera: must have shape \(4, 4\) or \(3, 4\), got \(3, 3\)"),
])
def test_bad_cameras(k, w, message):
    with pytest.raises(vcar.Error, match=message) as e:
        vcar.Camera(k, w, 160, 120, "cam7")
    assert "cam7" in str(e.value)


def test_bad_lists_and_sizes():
    with pytest.raises(vcar.Error, match="image size must be positive"):
        vcar.Camera(K, np.eye(4), 0, 120)
    c = vcar.Camera(K, np.eye(4), 160, 120, "a")
    s = vcar.Scene(np.zeros((1, 3), np.float32), np.array([[1, 0, 0, 0]], np.float32), np.zeros((1, 3), np.float32),
                   np.zeros(1, np.float32))
    with pytest.raises(vcar.Error, match=r"cameras: \[1\] is a str, expected vcar.Camera"):
        vcar.segment(s, [c, "b"], None, lambda r: [None] * len(r))
    with pytest.raises(vcar.Error, match="expected a list of vcar.Camera, got one camera"):
        vcar.segment(s, c, None, lambda r: [None])
    with pytest.raises(vcar.Error, match="no such file or folder"):
        vcar.read_cameras(os.path.join("no", "such", "cameras.json"))
