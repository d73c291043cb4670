"""Plug-ins written in Python.

A class deriving from prt.Basis or prt.Compressor, registered under a name,
is a plug-in like the C++ ones: scene files run through this module name it,
its keyword parameters are validated from its `parameters` schema with the
same messages, and prt.testing runs the conformance kit on it.

    @prt.register_basis("zonal", description="zonal harmonics")
    class Zonal(prt.Basis):
        parameters = {"order": prt.integer(4, min=1, max=30, help="bands")}
        def __init__(self, order):
            super().__init__()
            self.order = order
        def size(self): ...
        def orthonormal(self): return True
        def evaluate(self, directions): ...   # s x 3 -> s x size()
"""
import inspect

from . import _prt


def _text(value):
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(repr(float(v)) for v in value) + "]"
    return str(value)


def integer(default=None, *, min=-2**53, max=2**53, help="", required=False):
    """An integer parameter in [min, max]."""
    return dict(type="integer", default=_text(default), min=min, max=max, help=help,
                required=required)


def real(default=None, *, min=-1e300, max=1e300, help="", required=False):
    """A real parameter in [min, max]."""
    return dict(type="real", default=_text(default), min=min, max=max, help=help,
                required=required)


def boolean(default=False, *, help=""):
    return dict(type="boolean", default=_text(bool(default)), help=help)


def choice(default, choices, *, help=""):
    """A string from `choices` (a list of words)."""
    return dict(type="string", default=str(default), choices="|".join(choices), help=help)


def text(default="", *, help="", required=False):
    return dict(type="string", default=str(default or ""), help=help,
                required=required)


def reals(default=None, *, length=0, min=-1e300, max=1e300, help=""):
    """A list of reals (length 0: any length; one number is broadcast)."""
    # The schema writes a list default without its brackets ("1, 2"), as C++ plug-ins do.
    if isinstance(default, (list, tuple)):
        text = ", ".join(repr(float(v)) for v in default)
    else:
        text = _text(default)
    return dict(type="reals", default=text, length=length, min=min, max=max, help=help)


def _specs(cls):
    parameters = getattr(cls, "parameters", {}) or {}
    if not isinstance(parameters, dict):
        raise TypeError(f"{cls.__name__}.parameters must be a dict: name -> prt.integer(...) etc.")
    specs = []
    for name, spec in parameters.items():
        if not isinstance(spec, dict) or "type" not in spec:
            raise TypeError(f"{cls.__name__}.parameters[{name!r}] must be made by prt.integer, "
                            "prt.real, prt.boolean, prt.choice, prt.text or prt.reals")
        specs.append(dict(spec, name=name))
    return specs


def _register(kind, name, cls, description, version):
    origin = f"{cls.__module__}.{cls.__qualname__}"
    try:
        origin = f"{inspect.getsourcefile(cls)}: {origin}"
    except (TypeError, OSError):  # defined in a -c string or a notebook cell
        pass
    cls.plugin_name = name
    _prt.register_plugin(kind, name, cls, _specs(cls), description or (cls.__doc__ or "").strip()
                         .split("\n")[0][:150], version, origin)
    return cls


def register_basis(name, *, description="", version="1.0.0"):
    """Class decorator: registers a prt.Basis subclass as basis plug-in `name`.
    Registering a name again replaces the earlier class (re-running a cell)."""
    return lambda cls: _register("basis", name, cls, description, version)


def register_compressor(name, *, description="", version="1.0.0"):
    """Class decorator: registers a prt.Compressor subclass as compressor plug-in `name`."""
    return lambda cls: _register("compressor", name, cls, description, version)


def unregister(kind, name):
    """Removes a Python plug-in registration."""
    _prt.unregister_plugin(kind, name)
