"""`cmake --install` puts the module where the interpreter it was built for finds it."""
import os
import subprocess

import pytest

BUILD_DIR = os.environ.get("VCAR_BUILD_DIR")
PREFIX = os.environ.get("VCAR_INSTALL_PREFIX")
SITE = os.environ.get("VCAR_PYTHON_INSTALL_DIR")
PYTHON = os.environ.get("VCAR_PYTHON_EXECUTABLE", "/usr/bin/python3")
CMAKE = os.environ.get("CMAKE_COMMAND", "cmake")

pytestmark = pytest.mark.skipif(not (BUILD_DIR and PREFIX and SITE), reason="run by ctest (needs the build's settings)")


def site_dir(root=""):
    return os.path.join(root + PREFIX, SITE) if not os.path.isabs(SITE) else root + SITE


def test_install_dir_is_on_the_interpreters_path():
    # Without PYTHONPATH, what the interpreter searches for the configured prefix.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    path = subprocess.run([PYTHON, "-c", "import sys; print('\\n'.join(sys.path))"], env=env, capture_output=True,
                          text=True, check=True).stdout.split("\n")
    assert os.path.realpath(site_dir()) in [os.path.realpath(p) for p in path if p], (site_dir(), path)


def test_installed_module_imports_and_works(tmp_path):
    # DESTDIR: the tree `cmake --install` would write under the prefix, relocated into tmp_path.
    env = dict(os.environ, DESTDIR=str(tmp_path))
    subprocess.run([CMAKE, "--install", BUILD_DIR, "--component", "python"], env=env, check=True,
                   capture_output=True)
    installed = site_dir(str(tmp_path))
    files = sorted(os.listdir(os.path.join(installed, "vcar")))
    assert "__init__.py" in files and "synth.py" in files and "eval.py" in files
    assert any(f.startswith("_vcar.") and f.endswith(".so") for f in files), files
    code = ("import vcar, numpy as np\n"
            "print(vcar.__file__)\n"
            "w = vcar.synth.generate_world(seed=2, n_gaussians=500)\n"
            "print(len(w.scene), w.scene.means.dtype, vcar.__version__)\n")
    env = dict(os.environ, PYTHONPATH=installed)
    out = subprocess.run([PYTHON, "-c", code], env=env, cwd=str(tmp_path), capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    where, line = out.stdout.strip().split("\n")
    assert os.path.realpath(where).startswith(os.path.realpath(installed))
    n, dtype, version = line.split()
    assert n == "500" and dtype == "float32" and version[0].isdigit()
