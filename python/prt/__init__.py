"""PRT: precomputed radiance transfer from Python.

The stages of the bake and viewing pipelines, the plug-in registry and bake
files, with numpy arrays; and bases and compressors written in Python
(docs/python.md).

    import prt
    scene = prt.Scene("scenes/bunny.toml")
    data = prt.bake(scene)
    image = prt.render(scene, data)["image"]
"""
import atexit as _atexit
import pathlib as _pathlib

from . import _prt
from ._prt import (Basis, BakeData, Camera, CompressedTransfer, CompressionReport, Compressor,
                   DirectionSet, Environment, Error, Mesh, PluginRecord, Relighting, Renderer,
                   Scene, Traced, TransferSignal, create_basis, create_compressor,
                   create_renderer, exact_form, measure, plugin_problems, write_png)
from .plugins import (boolean, choice, integer, real, reals, register_basis,
                      register_compressor, text, unregister)
from .progress import ProgressPrinter, progress_to, tqdm_progress
from .scene_dict import scene_from_dict, scene_replace, scene_to_dict

__all__ = [
    "Basis", "BakeData", "Camera", "CompressedTransfer", "CompressionReport", "Compressor",
    "DirectionSet", "Environment", "Error", "Mesh", "PluginRecord", "Relighting", "Renderer",
    "Scene", "Traced", "TransferSignal", "bake", "compress", "create_basis", "create_compressor",
    "create_renderer", "exact_form", "ground_truth_vertices", "measure", "plugins",
    "reference_radiance",
    "plugin_problems", "read_bake", "render", "render_ground_truth", "trace", "write_png",
    "register_basis", "register_compressor", "unregister", "boolean", "choice", "integer", "real",
    "reals", "text", "tqdm_progress", "ProgressPrinter", "progress_to",
]

# Python plug-ins hold Python objects; drop them before the interpreter goes.
_atexit.register(_prt.unregister_all_python_plugins)

Scene.from_dict = staticmethod(scene_from_dict)
Scene.to_dict = scene_to_dict
Scene.replace = scene_replace


def plugins(kind=None):
    """Every plug-in found (C++ libraries and Python classes), as dicts with
    kind, name, version, description, file, python and parameters."""
    if kind not in (None, "basis", "compressor", "renderer"):
        raise ValueError(f"unknown plug-in kind {kind!r} (basis, compressor or renderer)")
    return [p for p in _prt.plugins() if kind is None or p["kind"] == kind]


def read_bake(file):
    """Reads a bake file (checked: format version, checksum, shapes)."""
    return BakeData.read(_pathlib.Path(file))


def trace(scene, *, progress=None, log=None):
    """Rays for the scene: visibility bits (and hits); pass to bake(traced=...)."""
    with progress_to(progress) as quiet:
        return _prt.trace(scene, quiet=quiet, log=log)


def bake(scene, *, output=None, force=False, restart=False, compress=True, traced=None,
         progress=None, log=None, timings=None):
    """plan -> rays -> transfer -> compression, as `prt bake` runs it.

    output: also write the bake file there (refused if it is one of the
    scene's inputs, or an existing file that is not a bake, unless force),
    through a checkpoint folder beside it as `prt bake` does: a bake killed
    or interrupted after it kept a part resumes when rerun (restart=True
    discards the kept parts).
    compress=False keeps the exact transfer as the compressed form.
    traced: rays from trace(scene), reused instead of traced again.
    progress: None (bars on stderr), False (none), "tqdm", or a callable
    receiving a dict per update. timings: a dict to receive stage -> seconds.
    """
    with progress_to(progress) as quiet:
        data, times = _prt.bake(scene, output=None if output is None else _pathlib.Path(output),
                                force=force, restart=restart, compress=compress,
                                traced=traced, quiet=quiet, log=log)
    if timings is not None:
        timings.update(times)
    return data


def compress(signal, compressor, mesh=None, *, progress=None, **parameters):
    """Encodes a transfer (a TransferSignal, or a v x n array) with a
    compressor (an object, or a name with keyword parameters):
    returns (CompressedTransfer, CompressionReport)."""
    if not isinstance(signal, TransferSignal):
        signal = TransferSignal(signal)
    if isinstance(compressor, str):
        compressor = create_compressor(compressor, **parameters)
    elif parameters:
        raise TypeError("keyword parameters are for a compressor given by name")
    with progress_to(progress):
        return _prt.compress(signal, compressor, mesh)


def render(scene, data, *, progress=None, log=None):
    """The scene's view of a bake as `prt render` draws it: a dict with
    image (height x width x 3, linear float32), vertex_radiance (v x 3),
    statistics and times."""
    with progress_to(progress) as quiet:
        return _prt.render(scene, data, quiet=quiet, log=log)


def render_ground_truth(scene, mesh=None, *, progress=None, log=None):
    """The Monte Carlo ground truth, as `prt render --ground-truth` draws it."""
    with progress_to(progress) as quiet:
        return _prt.render_ground_truth(scene, mesh, quiet=quiet, log=log)


def ground_truth_vertices(scene, mesh, lighting, camera, *, progress=None):
    """Monte Carlo radiance per vertex toward the camera (v x 3)."""
    with progress_to(progress) as quiet:
        return _prt.ground_truth_vertices(scene, mesh, lighting, camera, quiet=quiet)


def reference_radiance(scene, mesh, lighting, camera, *, progress=None, cache=None):
    """The Monte Carlo reference with its error bar, as `prt render --compare`
    measures against: a dict with radiance and standard_error (v x 3),
    noise_floor (the standard error's per-vertex RMS: an RMS against this
    reference below about twice it is not resolved), samples, batches and
    cached (the file it was read from, or None). cache: a folder of
    references to reuse and keep, as `--cache` (None: trace, keep nothing)."""
    with progress_to(progress) as quiet:
        return _prt.reference_radiance(scene, mesh, lighting, camera, quiet=quiet,
                                       cache=None if cache is None else str(cache))
