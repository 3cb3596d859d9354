"""Shared fixtures of the Python tests (run by ctest as python/<file>, see python/CMakeLists.txt).

Environment (set by ctest): PYTHONPATH=<build>/python, VCAR_CLI (the built `vcar` program),
VCAR_SOURCE_DIR, VCAR_TEST_DATA_DIR, VCAR_BUILD_DIR."""
import json
import os
import subprocess

import numpy as np
import pytest

import vcar

SOURCE_DIR = os.environ.get("VCAR_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
DATA_DIR = os.environ.get("VCAR_TEST_DATA_DIR", os.path.join(SOURCE_DIR, "tests", "data"))

# The small synthetic dataset of the CLI tests (examples/vcar_cli/tests.cmake).
SYNTH = dict(rig="forward", seed=3, gaussians=4000, views=8, width=160, height=120)


def cli_path():
    path = os.environ.get("VCAR_CLI")
    if not path or not os.path.exists(path):
        pytest.skip("the `vcar` program is not built (VCAR_BUILD_EXAMPLES=OFF): nothing to compare with")
    return path


def run_cli(*args):
    """Runs `vcar -q ARGS`, fails the test with its output on a non-zero exit, returns stdout."""
    p = subprocess.run([cli_path(), "-q", *map(str, args)], capture_output=True, text=True)
    assert p.returncode == 0, "vcar %s: exit %d\n%s%s" % (" ".join(map(str, args)), p.returncode, p.stdout, p.stderr)
    return p.stdout


@pytest.fixture(scope="session")
def cli_dataset(tmp_path_factory):
    """A dataset written by `vcar synth` (the command line, not the Python module)."""
    out = tmp_path_factory.mktemp("cli") / "dataset"
    run_cli("synth", "--rig", SYNTH["rig"], "--seed", SYNTH["seed"], "--gaussians", SYNTH["gaussians"],
            "--views", SYNTH["views"], "--width", SYNTH["width"], "--height", SYNTH["height"], "--out", out)
    return str(out)


@pytest.fixture(scope="session")
def world():
    return vcar.synth.generate_world(seed=SYNTH["seed"], n_gaussians=SYNTH["gaussians"])


@pytest.fixture(scope="session")
def rig(world):
    return vcar.synth.make_rig(SYNTH["rig"], world, width=SYNTH["width"], height=SYNTH["height"],
                               n_train=SYNTH["views"], seed=SYNTH["seed"])


def read_json(path):
    with open(path) as f:
        return json.load(f)


def selection_arrays(folder):
    """indices, scores, log_scales of a selection.json written by `vcar segment`, as the module's dtypes."""
    sel = read_json(os.path.join(folder, "selection.json"))
    return (np.array(sel["indices"], dtype=np.int64), np.array(sel["scores"], dtype=np.float32),
            np.array(sel["log_scales"], dtype=np.float32).reshape(-1, 3))
