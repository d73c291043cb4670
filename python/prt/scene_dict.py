"""Scenes built from Python dicts: written as TOML text and parsed by the
same parser as scene files, so every key gets the same checks and messages."""
import json
import pathlib
import tomllib

from . import _prt


def _value(value, where):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, (str, pathlib.PurePath)):
        return json.dumps(str(value))
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v, where) for v in value) + "]"
    if hasattr(value, "tolist"):  # numpy arrays and scalars
        return _value(value.tolist(), where)
    raise TypeError(f"scene dict: {where}: cannot write a {type(value).__name__} to a scene")


def to_toml(scene):
    """TOML text of a scene dict: {section: {key: value}}; a list of dicts
    (e.g. lighting.point) becomes an array of tables."""
    lines = []

    def table(name, body):
        scalars = {k: v for k, v in body.items() if not isinstance(v, dict) and
                   not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))}
        lines.append(f"[{name}]")
        for key, value in scalars.items():
            lines.append(f"{key} = {_value(value, name + '.' + key)}")
        lines.append("")
        for key, value in body.items():
            if isinstance(value, dict):
                table(f"{name}.{key}", value)
            elif key not in scalars:
                for item in value:
                    lines.append(f"[[{name}.{key}]]")
                    for k, v in item.items():
                        lines.append(f"{k} = {_value(v, name + '.' + key + '.' + k)}")
                    lines.append("")

    for section, body in scene.items():
        if not isinstance(body, dict):
            raise TypeError(f"scene dict: section \"{section}\" must be a dict of keys")
        table(section, body)
    return "\n".join(lines)


def scene_from_dict(scene, base=None, name="scene-from-dict.toml"):
    """A prt.Scene from {section: {key: value}} (the scene file's layout).
    Relative paths resolve against `base` (default: the current folder);
    messages name `name` in that folder."""
    folder = pathlib.Path(base) if base is not None else pathlib.Path.cwd()
    return _prt.Scene.parse(to_toml(scene), folder.resolve() / name)


def scene_to_dict(scene):
    """The scene's text as a dict (edit it and build another with from_dict)."""
    return tomllib.loads(scene.text)
