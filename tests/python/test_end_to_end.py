"""Bakes and renders from Python equal the CLI's on the same scene, and the
Python plug-ins bake the bunny through scene files."""
import filecmp
import subprocess

import numpy as np
import pytest
from conftest import bunny_scene

import kmeans_svd  # noqa: F401
import prt
import zonal_basis  # noqa: F401


def test_python_bake_and_render_equal_the_cli(cli, tmp_path):
    scene_file = bunny_scene(tmp_path, 'plugin = "cpca"\nclusters = 32\ncomponents = 6\n')
    subprocess.run([cli, "-q", "bake", str(scene_file), "-o", str(tmp_path / "cli.h5")],
                   check=True)
    subprocess.run([cli, "-q", "render", str(scene_file), "--bake", str(tmp_path / "cli.h5"),
                    "-o", str(tmp_path / "cli.png")], check=True)
    scene = prt.Scene(scene_file)
    data = prt.bake(scene, output=tmp_path / "python.h5", progress=False)
    assert filecmp.cmp(tmp_path / "cli.h5", tmp_path / "python.h5", shallow=False), \
        "the bake files differ"
    cli_data = prt.read_bake(tmp_path / "cli.h5")
    assert data.metrics["squared_error"] == cli_data.metrics["squared_error"] > 0
    image = prt.render(scene, data, progress=False)["image"]
    prt.write_png(image, tmp_path / "python.png", exposure=0.7)
    assert filecmp.cmp(tmp_path / "cli.png", tmp_path / "python.png", shallow=False), \
        "the images differ"


def test_zonal_bake_equals_the_sh_bakes_zonal_coefficients(tmp_path, root):
    """A basis in numpy, named in a scene file, baked on the bunny: its
    transfer is the m = 0 column of the C++ SH plug-in's (same rays)."""
    order = 6
    sh_scene = prt.Scene(bunny_scene(tmp_path, 'plugin = "none"').__fspath__())
    d = sh_scene.to_dict()
    d["basis"] = {"plugin": "sh", "order": order}
    sh = prt.bake(prt.Scene.from_dict(d, base=tmp_path), progress=False)
    d["basis"] = {"plugin": "numpy_zonal", "order": order, "axis": "z"}
    zonal = prt.bake(prt.Scene.from_dict(d, base=tmp_path), progress=False)
    columns = [l * (l + 1) for l in range(order)]
    expected = sh.transfer.coefficients[:, columns]
    assert zonal.transfer.coefficients.shape == expected.shape
    np.testing.assert_allclose(zonal.transfer.coefficients, expected, atol=2e-5, rtol=1e-4)
    # And it renders: zonal light is the SH light's m = 0 part.
    image = prt.render(prt.Scene.from_dict(d, base=tmp_path), zonal, progress=False)["image"]
    assert np.isfinite(image).all() and image.mean() > 0


def test_kmeans_svd_compares_with_the_cpp_static_cpca(tmp_path):
    """The numpy compressor bakes the bunny through a scene file; at the same
    budget its error is within a small factor of the C++ static CPCA's
    (both: VQ/k-means clusters, then PCA per cluster)."""
    scene = prt.Scene(bunny_scene(tmp_path, 'plugin = "kmeans_svd"\nclusters = 32\n'
                                  'components = 6\n'))
    python = prt.bake(scene, progress=False)
    cpp, report = prt.compress(python.transfer, "cpca", mesh=python.mesh, method="static",
                               clusters=32, components=6)
    mine = python.metrics["squared_error"]
    assert python.compressed.clusters == 32 and python.compressed.components == 6
    assert report.stored_floats == pytest.approx(python.compressed.stored_floats(), rel=1e-9)
    ratio = mine / report.squared_error
    print(f"SE kmeans_svd {mine:.6g}, cpca static {report.squared_error:.6g}, ratio {ratio:.3f}")
    assert 0.5 < ratio < 2.0
