"""The Monte Carlo reference's error bar (prt.reference_radiance): its
standard error predicts the reference's real error, falls at least as
1/sqrt(samples) (stratified: about samples^-3/4),
and a cached reference is the same reference."""
import textwrap

import numpy as np

import prt

BOX = textwrap.dedent("""
    [mesh]
    generate = "open-box"
    detail = 1
    [lighting]
    constant = [1, 0.8, 0.6]
    [ground_truth]
    samples = {samples}
    seed = {seed}
""")


def reference(tmp_path, samples, seed=7, cache=None):
    path = tmp_path / f"box_{samples}_{seed}.toml"
    path.write_text(BOX.format(samples=samples, seed=seed))
    scene = prt.Scene(str(path))
    mesh = scene.load_mesh()
    return prt.reference_radiance(scene, mesh, scene.load_environment(), scene.camera(mesh),
                                  cache=cache)


def rms(values):
    return float(np.sqrt(np.mean(np.sum(np.square(values), axis=1) / 3)))


def test_the_standard_error_predicts_the_real_error(tmp_path):
    coarse = reference(tmp_path, 64)
    fine = reference(tmp_path, 16384, seed=99)  # independent, 256 x the samples
    assert coarse["batches"] == 4 and coarse["samples"] == 64
    assert coarse["standard_error"].shape == coarse["radiance"].shape
    assert np.all(np.isfinite(coarse["standard_error"])) and coarse["noise_floor"] > 0
    # The coarse reference's real error (against one 16x more precise) is its
    # noise floor, within the spread a 4-batch estimate has.
    real = rms(coarse["radiance"] - fine["radiance"])
    assert 0.6 < real / coarse["noise_floor"] < 1.6, (real, coarse["noise_floor"])


def test_the_noise_floor_falls_as_one_over_root_samples(tmp_path):
    floors = [reference(tmp_path, n)["noise_floor"] for n in (64, 1024)]
    # 16 x the samples: at most 1/4 (1/sqrt), about 1/8 with stratification
    # (samples^-3/4 for the box's visibility edges); never below 1/16.
    assert 0.0625 < floors[1] / floors[0] < 0.3, floors


def test_a_cached_reference_is_the_same_reference(tmp_path):
    cache = tmp_path / "cache"
    first = reference(tmp_path, 64, cache=cache)
    second = reference(tmp_path, 64, cache=cache)
    other_seed = reference(tmp_path, 64, seed=8, cache=cache)
    assert first["cached"] is None and second["cached"] is not None
    assert np.array_equal(first["radiance"], second["radiance"])
    assert np.array_equal(first["standard_error"], second["standard_error"])
    assert other_seed["cached"] is None  # the seed is part of the key
    assert len(list(cache.iterdir())) == 2
