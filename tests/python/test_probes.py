"""A probe scene baked by the CLI as docs/receivers.md says, read from
Python: the receivers, the rows and the validity agree with each other."""
import subprocess

import numpy as np

import prt


def test_probe_bake_read_from_python(cli, root, tmp_path):
    scene = root / "scenes" / "room_probes.toml"
    subprocess.run([cli, "-q", "bake", str(scene), "-o", str(tmp_path / "probes.h5")],
                   check=True)
    data = prt.read_bake(tmp_path / "probes.h5")
    r = data.receivers
    assert r.kind == "probes"
    counts = tuple(r.counts)
    assert counts == (16, 6, 16)
    positions = r.positions
    assert positions.shape == (16 * 6 * 16, 3)
    # Row order: x fastest, then y, then z, at origin + spacing * index.
    assert np.allclose(positions[1] - positions[0], [r.spacing, 0, 0])
    assert np.allclose(positions[16] - positions[0], [0, r.spacing, 0])
    assert np.allclose(positions[0], r.origin)
    valid = r.valid
    rows = data.transfer.coefficients
    assert rows.shape == (len(valid), 9 * 100)  # incident order 3 x light order 10
    assert 0 < (~valid).sum() < len(valid)
    assert np.all(rows[~valid] == 0)
    # A valid probe may see no sky (on the floor behind the bunny, without
    # bounces), but most see some.
    assert (np.abs(rows[valid]).max(axis=1) > 0).mean() > 0.9
    # A bake at vertices says so.
    sphere = tmp_path / "sphere.toml"
    sphere.write_text('[mesh]\ngenerate = "sphere"\n[lighting]\nconstant = [1, 1, 1]\n'
                      '[transport]\nrays = 64\n')
    subprocess.run([cli, "-q", "bake", str(sphere), "-o", str(tmp_path / "sphere.h5")],
                   check=True)
    assert prt.read_bake(tmp_path / "sphere.h5").receivers.kind == "vertices"
