"""Issue 45's Python cases: a plug-in that keeps its arguments, a plug-in
that sleeps under Ctrl-C, paths that are not UTF-8, allocations too large:
each gives an exception with a message, never a crash or a wait."""
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import prt

SPHERE = textwrap.dedent("""
    [mesh]
    generate = "sphere"
    detail = 1
    [lighting]
    constant = [1, 1, 1]
    [basis]
    plugin = "{basis}"
    {basis_params}
    [transport]
    rays = 64
    [compressor]
    plugin = "{compressor}"
""")


def sphere_scene(tmp_path, basis="sh", basis_params="order = 3", compressor="none"):
    path = tmp_path / "scene.toml"
    path.write_text(SPHERE.format(basis=basis, basis_params=basis_params, compressor=compressor))
    return path


KEEPER = textwrap.dedent("""
    import sys, prt
    kept = []

    @prt.register_compressor("keeper")
    class Keeper(prt.Compressor):
        def encode(self, signal, mesh):
            kept.append((signal, mesh))
            return prt.exact_form(signal)

    data = prt.bake(prt.Scene(sys.argv[1]), progress=False)
    del data
    signal, mesh = kept[0]
    total = float(signal.coefficients.sum())
    print("kept", signal.vertices, signal.dimension, mesh.vertex_count, total > 0, flush=True)
""")


def test_a_compressor_may_keep_its_arguments(tmp_path):
    """The signal and mesh handed to encode() are Python's own: touching them
    after the bake reads valid values (it was a segfault in RowFile::matrix)."""
    scene = sphere_scene(tmp_path, compressor="keeper")
    for _ in range(3):
        run = subprocess.run([sys.executable, "-c", KEEPER, str(scene)], capture_output=True,
                             text=True, timeout=120, env=os.environ)
        assert run.returncode == 0, run.stdout + run.stderr
        words = run.stdout.split()
        assert words[0] == "kept" and words[1] == words[3] and words[4] == "True", run.stdout


SLEEPY = textwrap.dedent("""
    import sys, time, prt

    @prt.register_basis("sleepy")
    class Sleepy(prt.Basis):
        def size(self):
            return 4
        def orthonormal(self):
            return True
        def evaluate(self, directions):
            print("sleeping", flush=True)
            time.sleep(60)
            raise AssertionError("slept through Ctrl-C")

    try:
        prt.bake(prt.Scene(sys.argv[1]), progress=False)
    except KeyboardInterrupt:
        print("interrupted", flush=True)
        raise
""")


def test_ctrl_c_interrupts_a_sleeping_python_plugin(tmp_path):
    scene = sphere_scene(tmp_path, basis="sleepy", basis_params="")
    process = subprocess.Popen([sys.executable, "-c", SLEEPY, str(scene)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env=os.environ)
    try:
        assert process.stdout.readline().strip() == "sleeping"
        time.sleep(0.3)
        sent = time.monotonic()
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=30)
        waited = time.monotonic() - sent
    finally:
        process.kill()
    assert "interrupted" in out, out + err
    assert "KeyboardInterrupt" in err and process.returncode != 0
    assert waited < 1.0, f"took {waited:.2f} s to stop"


def test_a_path_that_is_not_utf8_gets_a_message(tmp_path):
    name = os.fsdecode(b"sc\xffene.toml")
    with pytest.raises(prt.Error) as error:
        prt.Scene(str(tmp_path / name))
    message = str(error.value)
    assert message and "\\xff" in message and "not found" in message, message


def test_an_allocation_too_large_is_a_prt_error_naming_it():
    basis = prt.create_basis("sh", order=200)
    directions = np.tile([[0.0, 0.0, 1.0]], (400000, 1))  # 400,000 x 40,000 doubles: 128 GB
    with pytest.raises(prt.Error) as error:
        basis.evaluate(directions)
    message = str(error.value)
    assert "evaluate" in message and "400000 x 40000" in message and "GB" in message, message
    assert basis.evaluate(directions[:10]).shape == (10, 40000)  # a size that fits still works
