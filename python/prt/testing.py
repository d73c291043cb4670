"""The conformance kit as pytest tests: the same checks as the C++ kit
(prt_basis_conformance, prt_compressor_conformance), one test per check.

    # test_zonal.py
    import zonal                      # registers basis "zonal"
    from prt.testing import basis_conformance
    test_zonal = basis_conformance("zonal")

Run: /usr/bin/python3 -m pytest test_zonal.py
"""
import pytest

from . import _prt


def checks(kind):
    """The kit's checks of a kind ("basis" or "compressor"): [(name, tags)]."""
    return _prt.conformance_checks(kind)


def run_check(kind, plugin, check):
    """Runs one check on a registered plug-in: its failures (empty: passes)."""
    return _prt.run_conformance_check(kind, plugin, check)


def run_all(kind, plugin):
    """Every check on a plug-in: {check: failures}, for scripts."""
    return {name: run_check(kind, plugin, name) for name, _ in checks(kind)}


def conformance(kind, plugin):
    """A pytest test function, parametrized over the kit's checks of `kind`,
    that runs each on `plugin`; assign it to a test_* name in a test module."""
    names = [name for name, _ in checks(kind)]

    @pytest.mark.parametrize("check", names, ids=[n.replace(" ", "_") for n in names])
    def test_conformance(check):
        failures = run_check(kind, plugin, check)
        if failures:
            pytest.fail(f"{kind} \"{plugin}\" fails \"{check}\":\n" + "\n".join(failures),
                        pytrace=False)

    test_conformance.__name__ = f"test_{kind}_{plugin}_conformance"
    return test_conformance


def basis_conformance(plugin):
    return conformance("basis", plugin)


def compressor_conformance(plugin):
    return conformance("compressor", plugin)
