"""examples/python: the synthetic example runs; the gsplat + SAM 2 wiring, with stand-ins for
gsplat's rasterization, torch and SAM 2's video predictor, gives what vcar's own renderer and
the oracle segmenter give."""
import contextlib
import importlib.util
import os

import numpy as np
import pytest

import vcar
from conftest import SOURCE_DIR

EXAMPLES = os.path.join(SOURCE_DIR, "examples", "python")


def load_example(name):
    spec = importlib.util.spec_from_file_location("example_" + name, os.path.join(EXAMPLES, name + ".py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_segment_synthetic_runs(tmp_path, capsys):
    example = load_example("segment_synthetic")
    assert example.main(["--gaussians", "4000", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    line = next(l for l in out.splitlines() if l.startswith("numpy colour picker"))
    selected = int(line.split()[3])
    assert selected > 0
    assert len(vcar.read_ply(str(tmp_path / "object.ply"))) == selected
    assert vcar.read_image(str(tmp_path / "object.png")).shape == (240, 320, 3)


class FakeTorch:
    """numpy arrays stand in for tensors; records the devices and contexts asked for."""
    bfloat16 = "bfloat16"

    def __init__(self):
        self.devices, self.contexts = set(), []

    def as_tensor(self, a, device=None):
        self.devices.add(device)
        return np.asarray(a)

    @contextlib.contextmanager
    def inference_mode(self):
        self.contexts.append("inference_mode")
        yield

    @contextlib.contextmanager
    def autocast(self, device, dtype=None):
        self.contexts.append(("autocast", device, dtype))
        yield


class FakeRasterization:
    """gsplat.rasterization's signature: checks that the arguments are gsplat's conventions for
    the scene's Gaussians (found back by their means) and renders them with vcar's CPU renderer."""

    def __init__(self, scene):
        self.scene = scene
        self.row = {m.tobytes(): i for i, m in enumerate(scene.means)}
        assert len(self.row) == len(scene), "the stand-in needs distinct means"
        self.calls = []

    def __call__(self, means, quats, scales, opacities, colors, viewmats, Ks, width, height, sh_degree,
                 render_mode="RGB", **others):
        s = self.scene
        assert not others
        for a in (means, quats, scales, opacities, colors, viewmats, Ks):
            assert a.dtype == np.float32
        assert viewmats.shape == (1, 4, 4) and Ks.shape == (1, 3, 3) and render_mode in ("RGB", "RGB+D")
        idx = np.array([self.row[m.tobytes()] for m in means], dtype=np.int64)
        np.testing.assert_array_equal(quats, s.quats[idx])  # w x y z, as gsplat
        np.testing.assert_array_equal(colors, s.sh[idx])
        assert colors.shape == (len(idx), (sh_degree + 1) ** 2, 3)
        np.testing.assert_allclose(opacities, 1 / (1 + np.exp(-s.opacities[idx].astype(np.float64))), rtol=1e-6)
        log_scales = np.log(scales.astype(np.float64))
        own_scales = np.allclose(log_scales, s.log_scales[idx], rtol=0, atol=1e-6)
        subset = None if np.array_equal(idx, np.arange(len(s))) else idx
        cam = vcar.Camera(Ks[0], viewmats[0], width, height)
        self.calls.append((cam, subset is not None, render_mode))
        out = vcar.render(s, cam, subset=subset, log_scales=None if own_scales else log_scales.astype(np.float32),
                          depth=render_mode == "RGB+D")
        img = out["rgb"] if render_mode == "RGB" else np.concatenate([out["rgb"], out["depth"][..., None]], axis=2)
        return img[None], out["alpha"][None, ..., None], {}


class FakeSam2:
    """SAM 2's video predictor API. Its masks are the target's visible masks in the synthetic
    world for the cameras the renderer drew the frames from (the frames are rendered just before)."""

    def __init__(self, world, rasterization):
        self.world, self.rasterization = world, rasterization
        self.prompts = []

    def init_state(self, video_path):
        files = sorted(os.listdir(video_path))
        n = len(files)
        assert files == ["%05d.jpg" % k for k in range(n)]  # SAM 2's loader: JPEGs named by index
        cams = [c for c, _, _ in self.rasterization.calls[-n:]]
        for k in (0, n - 1):  # the frames are those renders (JPEG: close, not equal)
            frame = vcar.read_image(os.path.join(video_path, files[k]))
            cam = cams[k]
            rgb = vcar.render(self.world.scene, cam, subset=None)["rgb"]
            assert frame.shape == (cam.height, cam.width, 3)
            if not self.rasterization.calls[-n + k][1]:
                assert np.abs(frame.astype(np.float32) - np.clip(rgb, 0, 1) * 255).mean() < 4
        return {"cameras": cams}

    def add_new_points_or_box(self, inference_state, frame_idx, obj_id, points=None, labels=None, box=None):
        self.prompts.append((frame_idx, obj_id, points, labels, box))

    def propagate_in_video(self, state):
        assert self.prompts and self.prompts[-1][0] == 0 and self.prompts[-1][1] == 1
        for k, cam in enumerate(state["cameras"]):
            mask = self.world.visible_mask(cam)
            yield k, [1], np.where(mask, 8.0, -8.0).astype(np.float32)[None, None]  # (objects, 1, H, W)


def test_gsplat_sam2_wiring_with_stand_ins(world, rig):
    example = load_example("gsplat_sam2")
    torch = FakeTorch()
    rasterization = FakeRasterization(world.scene)
    sam2 = FakeSam2(world, rasterization)
    prompt = vcar.synth.prompt_points(world.visible_mask(rig.train[rig.reference]), rig.reference, n_points=2)
    renderer = example.gsplat_renderer(world.scene, device="cuda:0", rasterization=rasterization, torch=torch)
    segmenter = example.sam2_segmenter(sam2, torch=torch)

    wired = vcar.segment(world.scene, rig.train, prompt, segmenter, renderer=renderer)
    own = vcar.segment(world.scene, rig.train, prompt, vcar.synth.OracleSegmenter(world, mode="visible"))
    assert len(own["indices"]) > 0
    for key in ("indices", "scores", "log_scales"):
        np.testing.assert_array_equal(wired[key], own[key])

    assert torch.devices == {"cuda:0"}
    assert "inference_mode" in torch.contexts and ("autocast", "cuda", "bfloat16") in torch.contexts
    assert any(depth == "RGB+D" for _, _, depth in rasterization.calls)  # the default preset's occlusion test
    assert any(sub for _, sub, _ in rasterization.calls)  # the fine round draws the coarse selection alone
    frame_idx, obj_id, points, labels, box = sam2.prompts[0]
    np.testing.assert_array_equal(points, np.asarray(prompt["points"], np.float32))
    np.testing.assert_array_equal(labels, [1, 1])
    assert box is None


def test_sam2_segmenter_refuses_an_empty_prompt(world, rig):
    example = load_example("gsplat_sam2")
    segmenter = example.sam2_segmenter(FakeSam2(world, FakeRasterization(world.scene)), torch=FakeTorch())
    with pytest.raises(ValueError, match="points or a box"):
        vcar.segment(world.scene, rig.train, {"text": "the mug"}, segmenter)
