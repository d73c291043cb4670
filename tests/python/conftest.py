"""Shared fixtures of the Python tests. ctest runs them with PYTHONPATH set
to the build tree's package folder and PRT_CLI / PRT_SOURCE_DIR set."""
import os
import pathlib
import sys

import pytest

ROOT = pathlib.Path(os.environ.get("PRT_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
sys.path.insert(0, str(ROOT / "examples" / "python"))  # zonal_basis, kmeans_svd
sys.path.insert(0, str(pathlib.Path(__file__).parent))  # wrong_plugins


@pytest.fixture
def root():
    return ROOT


@pytest.fixture
def cli():
    path = os.environ.get("PRT_CLI")
    if not path:
        pytest.skip("PRT_CLI is not set (ctest sets it)")
    return path


def bunny_scene(tmp_path, compressor, extra=""):
    """The default scene with another compressor, written to tmp_path with
    absolute paths (so the CLI and Python read the same file)."""
    text = (ROOT / "scenes" / "bunny.toml").read_text()
    text = text.replace("../data/", str(ROOT / "data") + "/")
    text = text.replace('[compressor]\nplugin = "none"', "[compressor]\n" + compressor)
    text = text.replace('bake = "../out/bunny.h5"', f'bake = "{tmp_path}/bunny.h5"')
    text = text.replace('image = "../out/bunny.png"', f'image = "{tmp_path}/bunny.png"')
    path = tmp_path / "scene.toml"
    path.write_text(text + extra)
    return path
