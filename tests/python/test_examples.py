"""The documented example script runs to its plot, and the notebook runs."""
import os
import subprocess
import sys

import pytest


def test_example_script_runs_to_its_plot(root, tmp_path):
    out = tmp_path / "out"
    subprocess.run([sys.executable, str(root / "examples" / "python" / "error_vs_bytes.py"),
                    "--quick", "--out", str(out)], check=True, env=os.environ)
    for name in ("error_vs_bytes.png", "images.png"):
        assert (out / name).stat().st_size > 10000, name


def test_notebook_runs(root):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    notebook = nbformat.read(root / "examples" / "python" / "tour.ipynb", as_version=4)
    nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(root)}}).execute()
    images = [o for cell in notebook.cells if cell.cell_type == "code"
              for o in cell.get("outputs", []) if "image/png" in o.get("data", {})]
    assert len(images) == 2  # the plot and the image
