"""Plug-ins written in Python: the conformance kit passes the examples and
fails the deliberately wrong ones; their errors are clear, never a crash."""
import numpy as np
import pytest

import kmeans_svd  # noqa: F401  registers compressor "kmeans_svd"
import prt
import wrong_plugins  # noqa: F401  registers the wrong ones
import zonal_basis  # noqa: F401  registers basis "numpy_zonal"
from prt.testing import basis_conformance, compressor_conformance, run_all, run_check

# The same checks as the C++ kit, one pytest test each.
test_zonal_conformance = basis_conformance("numpy_zonal")
test_kmeans_svd_conformance = compressor_conformance("kmeans_svd")


def test_kit_runs_the_cpp_checks_on_cpp_plugins_too():
    assert all(not failures for failures in run_all("basis", "sh").values())


def test_kit_fails_a_basis_missing_its_normalisation():
    failures = run_check("basis", "zonal_unnormalised",
                         "an orthonormal basis has an identity Gram matrix")
    assert failures and "Identity" in failures[0]


def test_kit_fails_a_compressor_with_an_inconsistent_form():
    failures = run_check("compressor", "keeps_mean_only", "the compressed form is consistent and "
                         "finite")
    text = "\n".join(failures)
    assert failures and "inconsistent form" in text
    # It names the array and its shape against the signal's.
    assert "cluster_of_vertex has" in text and "entries for" in text, text


def test_wrong_shape_is_one_clear_error():
    """What Python returns is checked where C++ calls it (here the default
    projection, which evaluates the basis on the set's directions)."""
    basis = prt.create_basis("wrong_shape")
    with pytest.raises(prt.Error, match=r'basis "wrong_shape" \(Python class WrongShape\): '
                                        r"evaluate\(\) returned a 5 x 2 array; expected 5 x 3"):
        basis.projection_matrix(prt.DirectionSet.fibonacci(5))


def test_python_parameters_are_validated_like_cpp_ones():
    with pytest.raises(prt.Error, match=r'basis "numpy_zonal": parameter "axis" = "w"'):
        prt.create_basis("numpy_zonal", axis="w")
    with pytest.raises(prt.Error, match=r'"order" = 0 is out of range \[1, 60\]'):
        prt.create_basis("numpy_zonal", order=0)
    zonal = next(p for p in prt.plugins("basis") if p["name"] == "numpy_zonal")
    assert zonal["python"] and "zonal_basis.py" in zonal["file"]


def test_a_python_exception_names_the_plugin_and_method():
    @prt.register_basis("raises")
    class Raises(prt.Basis):
        def __init__(self):
            super().__init__()

        def size(self):
            return 1

        def evaluate(self, directions):
            raise ValueError("no values today")

    with pytest.raises(prt.Error, match=r'basis "raises" .*evaluate\(\) raised ValueError: no '
                                        r"values today"):
        prt.create_basis("raises").projection_matrix(prt.DirectionSet.fibonacci(3))
    prt.unregister("basis", "raises")
    with pytest.raises(prt.Error, match='no basis plug-in named "raises"'):
        prt.create_basis("raises")


def test_a_library_plugin_name_cannot_be_taken():
    class Fake(prt.Basis):
        pass

    with pytest.raises(prt.Error, match="the plug-in library .* has that name"):
        prt.register_basis("sh")(Fake)


def test_register_refuses_a_class_of_the_wrong_interface():
    class NotABasis:
        pass

    with pytest.raises(prt.Error, match="must be a class deriving from prt.Basis"):
        prt.register_basis("nope")(NotABasis)


def test_every_parameter_helper_registers_and_validates():
    @prt.register_basis("every_type")
    class EveryType(prt.Basis):
        parameters = {"flag": prt.boolean(True), "weights": prt.reals([1, 2], length=2),
                      "scale": prt.real(0.5, min=0, max=1), "mode": prt.choice("a", ["a", "b"]),
                      "label": prt.text("hello world")}

        def __init__(self, flag, weights, scale, mode, label):
            super().__init__()
            self.seen = (flag, weights, scale, mode, label)

        def size(self):
            return 1

        def evaluate(self, directions):
            return np.full((len(directions), 1), 1 / np.sqrt(4 * np.pi))

    assert prt.create_basis("every_type").seen == (True, [1.0, 2.0], 0.5, "a", "hello world")
    assert prt.create_basis("every_type", flag=False, weights=[3, 4]).seen[:2] == (False, [3, 4])
    with pytest.raises(prt.Error, match='"weights"'):
        prt.create_basis("every_type", weights=[1, 2, 3])
    prt.unregister("basis", "every_type")


@pytest.mark.parametrize("spec, message", [
    (prt.integer(5, min=0, max=3), r'"p" = 5 is out of range \[0, 3\] \(this is the schema\'s own '
                                   r'default'),
    (prt.integer(1, min=3, max=0), "min is above max"),
    (prt.choice("c", ["a", "b"]), r'"p" = "c" is not one of: a, b .*\(this is the schema\'s own '
                                  r'default'),
])
def test_bad_parameter_specs_are_refused_at_registration(spec, message):
    class Spec(prt.Basis):
        parameters = {"p": spec}

    with pytest.raises(prt.Error, match=message):
        prt.register_basis("bad_spec")(Spec)


def test_returning_none_or_wrong_bands_is_one_clear_error():
    @prt.register_compressor("returns_none")
    class ReturnsNone(prt.Compressor):
        def __init__(self):
            super().__init__()

        def encode(self, signal, mesh):
            return None

    with pytest.raises(prt.Error, match=r'compressor "returns_none" .*encode\(\) returned None'):
        prt.compress(np.ones((4, 3), np.float32), "returns_none")

    @prt.register_basis("bad_bands")
    class BadBands(zonal_basis.Zonal):
        def coefficient_bands(self):
            return [0]

    with pytest.raises(prt.Error, match=r"coefficient_bands\(\) returned 1 bands for 6"):
        prt.Scene  # the pipeline asks for bands where it windows a light
        prt.create_basis("bad_bands").save()  # save() is C++; bands next
        prt._prt.Basis.coefficient_bands(prt.create_basis("bad_bands"))


def test_a_library_name_is_refused_in_a_fresh_process():
    import subprocess
    import sys
    out = subprocess.run([sys.executable, "-c", "import prt\nclass B(prt.Basis): pass\n"
                          "prt.register_basis('sh')(B)"], capture_output=True, text=True)
    assert out.returncode != 0 and "has that name" in out.stderr


def test_the_kit_on_an_unknown_name_is_one_error():
    with pytest.raises(prt.Error, match='no basis plug-in named "nothing_here"'):
        run_check("basis", "nothing_here", "saved state restores an identical basis")
