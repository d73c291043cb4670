"""The bindings' round trips (numpy in, numpy out) and their errors."""
import numpy as np
import pytest

import prt


def test_mesh_round_trip_and_zero_copy_views():
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
    triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    mesh = prt.Mesh(positions, triangles)
    assert mesh.vertex_count == 4 and mesh.triangle_count == 4
    np.testing.assert_array_equal(mesh.positions, positions)
    np.testing.assert_array_equal(mesh.triangles, triangles)
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1)
    # Views of the C++ storage: the same memory each time, kept alive by the mesh.
    assert np.shares_memory(mesh.positions, mesh.positions)
    view = mesh.positions
    del mesh
    assert view[1, 0] == 1.0


def test_mesh_errors_name_what_is_wrong():
    with pytest.raises(prt.Error, match="triangle 0 uses vertex 7"):
        prt.Mesh(np.zeros((3, 3), np.float32), np.array([[0, 1, 7]]))
    with pytest.raises(prt.Error, match="n x 3"):
        prt.Mesh(np.zeros((3, 2), np.float32), np.array([[0, 1, 2]]))


def test_sh_basis_matches_closed_form_and_projects_back():
    sh = prt.create_basis("sh", order=3)
    d = np.array([[0.0, 0.6, 0.8], [1.0, 0.0, 0.0]])
    y = sh.evaluate(d)
    c = np.sqrt(3 / (4 * np.pi))
    np.testing.assert_allclose(y[:, 1:4], c * d[:, [1, 2, 0]], atol=1e-12)  # (y, z, x)
    rule = prt.DirectionSet.fibonacci(4000)
    coefficients = np.random.default_rng(1).normal(size=(2, sh.size()))
    samples = coefficients @ sh.evaluate(rule.directions).T
    np.testing.assert_allclose(sh.project(samples, rule), coefficients, atol=2e-3)
    assert rule.weights.sum() == pytest.approx(4 * np.pi)


def test_transfer_and_compressed_form_round_trip():
    x = np.random.default_rng(2).normal(size=(50, 9)).astype(np.float32)
    signal = prt.TransferSignal(x)
    np.testing.assert_array_equal(signal.coefficients, x)
    assert np.shares_memory(signal.coefficients, signal.coefficients)
    exact = prt.exact_form(signal)
    np.testing.assert_array_equal(exact.decode(), x)
    compressed, report = prt.compress(signal, "pca", components=9)
    assert report.squared_error < 1e-8 * (x.astype(np.float64) ** 2).sum()
    compressed, report = prt.compress(x, "pca", components=2)
    assert report.squared_error == pytest.approx(
        ((compressed.decode().astype(np.float64) - x) ** 2).sum(), rel=1e-5)
    assert compressed.weights.shape == (50, 2)


def test_compressed_form_checks_its_arrays():
    with pytest.raises(prt.Error):
        prt.CompressedTransfer("mine", 3, np.array([0, 5], np.int32),
                               np.zeros((2, 0), np.float32), np.zeros((1, 3), np.float32),
                               [np.zeros((0, 3), np.float32)]).validate(2)


def test_parameters_are_validated_as_in_scene_files():
    with pytest.raises(prt.Error, match=r'keyword ordr: error: basis "sh": unknown parameter '
                                        r'"ordr".*did you mean "order"'):
        prt.create_basis("sh", ordr=4)
    with pytest.raises(prt.Error, match=r'"order" = 0 is out of range'):
        prt.create_basis("sh", order=0)
    with pytest.raises(prt.Error, match='no basis plug-in named "hs"'):
        prt.create_basis("hs")
    with pytest.raises(prt.Error, match="cannot use a value of type dict"):
        prt.create_basis("sh", order={})


def test_plugins_lists_schemas():
    sh = next(p for p in prt.plugins("basis") if p["name"] == "sh")
    order = next(p for p in sh["parameters"] if p["name"] == "order")
    assert order["type"] == "integer" and order["min"] >= 1 and not sh["python"]


def test_scene_from_dict_is_checked_like_a_file(root):
    scene = prt.Scene(root / "scenes" / "bunny.toml")
    d = scene.to_dict()
    d["basis"]["order"] = 4
    again = prt.Scene.from_dict(d, base=root / "scenes")
    assert prt.read_bake  # the same API builds both
    assert again.basis().size() == 16
    d["basis"]["oder"] = 4
    with pytest.raises(prt.Error, match=r'scene-from-dict.toml:\d+:\d+: error: .*"oder"'):
        prt.Scene.from_dict(d, base=root / "scenes")


def test_bake_file_round_trip_and_output_safety(root, tmp_path):
    scene = prt.Scene(root / "scenes" / "bunny.toml")
    data = prt.bake(scene, compress=False, progress=False)
    out = tmp_path / "bake.h5"
    data.write(out)
    again = prt.read_bake(out)
    np.testing.assert_array_equal(again.transfer.coefficients, data.transfer.coefficients)
    np.testing.assert_array_equal(again.mesh.positions, data.mesh.positions)
    assert again.basis.name == "sh"
    # An output over the scene's own inputs is refused and nothing is written.
    before = (root / "scenes" / "bunny.toml").read_bytes()
    with pytest.raises(prt.Error, match="bunny.toml"):
        prt.bake(scene, output=root / "scenes" / "bunny.toml", progress=False)
    assert (root / "scenes" / "bunny.toml").read_bytes() == before
    with pytest.raises(prt.Error):
        data.write(tmp_path / "not-a-folder" / "x.h5")
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(prt.Error, match="notes.txt"):
        data.write(tmp_path / "notes.txt")
    assert (tmp_path / "notes.txt").read_text() == "mine"


def test_damaged_bake_file_is_refused(tmp_path):
    bad = tmp_path / "bad.h5"
    bad.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 100)
    with pytest.raises(prt.Error, match="bad.h5"):
        prt.read_bake(bad)


def test_stages_alone_relight_and_progress(root):
    scene = prt.Scene(root / "scenes" / "bunny.toml")
    reports = []
    traced = prt.trace(scene, progress=reports.append)
    assert traced.rays_cast > 0 and any(r["final"] for r in reports)
    data = prt.bake(scene, traced=traced, progress=False)
    relighting = prt.Relighting(scene, data)
    light = relighting.light(scene.load_environment())
    assert light.shape == (100, 3)
    camera = scene.camera(data.mesh)
    radiance = relighting.relight(data.compressed, light, camera)
    rendered = prt.render(scene, data, progress=False)
    np.testing.assert_allclose(radiance, rendered["vertex_radiance"], rtol=1e-6)
    assert relighting.view(data.compressed, camera) is None  # diffuse: relight() is the path
    # Twice the light, twice the radiance (transfer is linear in the light).
    np.testing.assert_allclose(relighting.relight(data.compressed, 2 * light, camera),
                               2 * radiance, rtol=1e-5, atol=1e-6)
    camera.width, camera.height = 64, 48
    image = relighting.render(data.compressed, light, camera, prt.create_renderer("cpu"))["image"]
    assert image.shape == (48, 64, 3) and np.isfinite(image).all()


def test_progress_callback_errors_surface(root):
    scene = prt.Scene(root / "scenes" / "bunny.toml")

    def fail(report):
        raise RuntimeError("callback broke")

    with pytest.raises(RuntimeError, match="callback broke"):
        prt.trace(scene, progress=fail)


# What a first review found: each was a crash, a silent wrong result or an
# unclear message before.

def test_empty_or_mismatched_inputs_are_refused(root):
    with pytest.raises(prt.Error, match="no columns"):
        prt.compress(np.zeros((10, 0), np.float32), "pca")
    mesh = prt.Scene(root / "scenes" / "bunny.toml").load_mesh()
    with pytest.raises(prt.Error, match="the mesh has 37706 vertices but the transfer 1 rows"):
        prt.compress(np.random.rand(1, 4), "none", mesh=mesh)
    with pytest.raises(prt.Error, match="cluster index out of range"):
        prt.CompressedTransfer("x", 4, np.full(3, 10**8, np.int32), np.zeros((3, 0), np.float32),
                               np.zeros((1, 4), np.float32), [np.zeros((0, 4), np.float32)])
    with pytest.raises(prt.Error, match="integer array"):
        prt.Mesh(np.zeros((3, 3), np.float32), np.array([[0, 1, 2.5]]))


def test_views_are_read_only(root):
    data = prt.bake(prt.Scene(root / "scenes" / "bunny.toml"), compress=False, progress=False)
    with pytest.raises(ValueError, match="read-only"):
        data.mesh.triangles[0, 0] = 10**9
    with pytest.raises(ValueError, match="read-only"):
        data.transfer.coefficients[0, 0] = 1
    copy = np.array(data.mesh.positions)
    copy[0] = 5  # a copy is the user's
    assert data.mesh.positions[0, 0] != 5


def test_rays_of_another_scene_are_refused(root):
    scene = prt.Scene(root / "scenes" / "bunny.toml")
    other = scene.replace({"transport": {"directions": "stratified", "rays": 64}})
    traced = prt.trace(other, progress=False)
    with pytest.raises(prt.Error, match="traced for another mesh, transport or material"):
        prt.bake(scene, traced=traced, progress=False)


def test_scene_replace_and_dict_errors_show_the_line(root):
    scene = prt.Scene(root / "scenes" / "bunny.toml")
    smaller = scene.replace({"basis": {"order": 3}})
    assert smaller.basis().size() == 9
    with pytest.raises(prt.Error, match=r"line \d+ of the TOML written from the dict: oder = 3"):
        scene.replace({"basis": {"oder": 3}})


def test_keyword_values_numpy_and_overflow():
    assert prt.create_basis("sh", order=np.int64(3)).size() == 9
    with pytest.raises(prt.Error, match="does not fit in 64 bits"):
        prt.create_basis("sh", order=10**30)


def test_camera_light_and_encoding_are_checked(root):
    scene = prt.Scene(root / "scenes" / "bunny.toml")
    data = prt.bake(scene, progress=False)
    relighting = prt.Relighting(scene, data)
    light = relighting.light(scene.load_environment())
    camera = scene.camera(data.mesh)
    for field, value in [("width", -1), ("fov_degrees", 0.0), ("fov_degrees", float("nan"))]:
        bad = scene.camera(data.mesh)
        setattr(bad, field, value)
        with pytest.raises(prt.Error, match="camera"):
            relighting.relight(data.compressed, light, bad)
    with pytest.raises(prt.Error, match="finite 100 x 3"):
        relighting.relight(data.compressed, light[:4], camera)
    with pytest.raises(prt.Error, match="6 coefficients per vertex"):
        data.compressed = prt.exact_form(prt.TransferSignal(np.zeros((37706, 6), np.float32)))
    environment = scene.load_environment()
    with pytest.raises(prt.Error, match="finite and non-negative"):
        environment.set_intensity(-1)
    with pytest.raises(prt.Error, match="rotation matrix"):
        environment.rotation = 2 * np.eye(3)
    environment.set_rotation_degrees(90)
    assert np.allclose(environment.rotation @ environment.rotation.T, np.eye(3))


def test_output_messages_name_the_python_keyword(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(prt.Error, match="use force=True to overwrite"):
        prt.write_png(np.zeros((2, 2, 3), np.float32), tmp_path / "notes.txt")


def test_unknown_kind_is_an_error():
    with pytest.raises(ValueError, match="unknown plug-in kind"):
        prt.plugins("nonsense")


GLOSSY_SPHERE = """
[mesh]
generate = "sphere"
detail = 2
[material]
brdf = "phong"
diffuse = 0.3
specular = 0.5
exponent = 8
[transport]
rays = 128
[basis]
plugin = "sh"
order = 4
[exit]
plugin = "hsh"
order = 3
[lighting]
constant = [1, 1, 1]
"""


def test_a_view_relights_glossy_transfer_for_many_lights(tmp_path):
    path = tmp_path / "glossy.toml"
    path.write_text(GLOSSY_SPHERE)
    scene = prt.Scene(str(path))
    data = prt.bake(scene, progress=False)
    relighting = prt.Relighting(scene, data)
    camera = scene.camera(data.mesh)
    view = relighting.view(data.compressed, camera)
    assert view.vertices == data.mesh.vertex_count
    assert view.light_space.shape == (data.mesh.vertex_count, 16)
    rng = np.random.default_rng(5)
    for _ in range(3):  # three lights, one camera
        light = rng.normal(size=(16, 3))
        expected = relighting.relight(data.compressed, light, camera)
        np.testing.assert_allclose(relighting.relight(view, light), expected,
                                   atol=1e-5 * np.abs(expected).max())
    with pytest.raises(prt.Error, match="finite 16 x 3"):
        relighting.relight(view, np.zeros((9, 3)))
