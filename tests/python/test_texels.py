"""A texel scene baked by the CLI as docs/receivers.md says, read from
Python: the atlas, the texels' points and the mesh's uvs agree."""
import subprocess

import numpy as np

import prt


def test_texel_bake_read_from_python(cli, root, tmp_path):
    scene = root / "scenes" / "nefertiti_texels.toml"
    subprocess.run([cli, "-q", "bake", str(scene), "-o", str(tmp_path / "texels.h5")],
                   check=True)
    data = prt.read_bake(tmp_path / "texels.h5")
    r = data.receivers
    assert r.kind == "texels"
    assert (r.width, r.height) == (32, 32)
    texels = r.texels
    rows = data.transfer.coefficients
    assert rows.shape == (len(texels), 100)
    assert np.all(np.diff(texels.astype(np.int64)) > 0)
    assert texels.max() < 32 * 32
    # CGAL's conformal map fills the square along one side: most texels lie on the face.
    assert 0.3 < len(texels) / (32 * 32) < 1.0
    uvs = data.mesh.uvs
    assert uvs.shape == (data.mesh.vertex_count, 2)
    assert uvs.min() >= 0 and uvs.max() <= 1
    # Each texel's point lies on the mesh, within a texel's reach of a vertex's place.
    points = r.positions
    assert points.shape == (len(texels), 3)
    nearest = np.min(np.linalg.norm(points[:, None, :] - data.mesh.positions[None], axis=2), axis=1)
    assert nearest.max() < 1.0
    assert np.allclose(np.linalg.norm(r.points.normals, axis=1), 1, atol=1e-4)
