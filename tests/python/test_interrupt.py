"""Ctrl-C stops a long call cleanly: KeyboardInterrupt within moments,
nothing written, and the module usable again."""
import os
import signal
import subprocess
import sys
import textwrap
import time

from conftest import bunny_scene

SCRIPT = textwrap.dedent("""
    import sys, prt
    scene = prt.Scene(sys.argv[1])
    print("started", flush=True)
    try:
        prt.bake(scene, output=sys.argv[2], progress=False)
        print("finished")
    except KeyboardInterrupt:
        print("interrupted", flush=True)
        data = prt.bake(prt.Scene(sys.argv[3]), progress=False)  # usable again
        print("then baked", data.mesh.vertex_count, flush=True)
        raise
""")


def test_ctrl_c_interrupts_a_bake(tmp_path):
    # 65k rays per vertex: about a minute of tracing, far longer than the test waits.
    slow = bunny_scene(tmp_path, 'plugin = "none"').read_text().replace("rays = 1024",
                                                                      "rays = 65536")
    (tmp_path / "slow.toml").write_text(slow)
    quick = tmp_path / "quick.toml"
    quick.write_text(slow.replace("rays = 65536", "rays = 64"))
    output = tmp_path / "out" / "slow.h5"
    output.parent.mkdir()
    process = subprocess.Popen([sys.executable, "-c", SCRIPT, str(tmp_path / "slow.toml"),
                                str(output), str(quick)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env=os.environ)
    assert process.stdout.readline().strip() == "started"
    time.sleep(2.0)
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    waited = time.monotonic() - sent
    assert "interrupted" in out and "then baked 37706" in out, out + err
    assert "KeyboardInterrupt" in err and process.returncode != 0
    assert waited < 10, f"took {waited:.1f} s to stop"
    assert list(output.parent.iterdir()) == [], "the interrupted bake left files behind"


COMPRESS = textwrap.dedent("""
    import sys, prt
    data = prt.bake(prt.Scene(sys.argv[1]), compress=False, progress=False)
    print("started", flush=True)
    try:
        prt.compress(data.transfer, "cpca", method="iterative", clusters=1024, components=8,
                     progress=False)
        print("finished")
    except KeyboardInterrupt:
        print("interrupted", flush=True)
""")


def test_ctrl_c_interrupts_a_compression(root):
    """Clustering iterations check for Ctrl-C too (iterative CPCA 1024 x 8 on
    the bunny takes minutes on two cores)."""
    process = subprocess.Popen([sys.executable, "-c", COMPRESS,
                                str(root / "scenes" / "bunny.toml")], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env=os.environ)
    assert process.stdout.readline().strip() == "started"
    time.sleep(3.0)
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=120)
    assert "interrupted" in out, out + err
    assert time.monotonic() - sent < 15
    assert "CPCA" not in err  # progress=False: no bars
