"""Scenes built from Python dicts: written as TOML text and parsed by the
same parser as scene files, so every key gets the same checks and messages."""
import json
import pathlib
import re
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


def _key(key):
    key = str(key)
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


def to_toml(scene):
    """TOML text of a scene dict: {section: {key: value}}; a list of dicts
    (e.g. lighting.point) becomes an array of tables."""
    lines = []

    def table(name, body):
        scalars = {k: v for k, v in body.items() if not isinstance(v, dict) and
                   not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))}
        lines.append(f"[{name}]")
        for key, value in scalars.items():
            lines.append(f"{_key(key)} = {_value(value, name + '.' + str(key))}")
        lines.append("")
        for key, value in body.items():
            if isinstance(value, dict):
                table(f"{name}.{_key(key)}", value)
            elif key not in scalars:
                for item in value:
                    lines.append(f"[[{name}.{_key(key)}]]")
                    for k, v in item.items():
                        lines.append(f"{_key(k)} = {_value(v, name + '.' + str(key) + '.' + str(k))}")
                    lines.append("")

    for section, body in scene.items():
        if not isinstance(body, dict):
            raise TypeError(f"scene dict: section \"{section}\" must be a dict of keys")
        table(_key(section), body)
    return "\n".join(lines)


def scene_from_dict(scene, base=None, name="scene-from-dict.toml"):
    """A prt.Scene from {section: {key: value}} (the scene file's layout).
    Relative paths resolve against `base` (default: the current folder);
    messages name `name` in that folder."""
    folder = pathlib.Path(base) if base is not None else pathlib.Path.cwd()
    text = to_toml(scene)
    try:
        return _prt.Scene.parse(text, folder.resolve() / name)
    except _prt.Error as error:
        # The location is in the TOML written from the dict: show that line.
        found = re.search(re.escape(name) + r":(\d+)", str(error))
        lines = text.split("\n")
        if found and 0 < int(found.group(1)) <= len(lines):
            raise _prt.Error(f"{error}\n  (line {found.group(1)} of the TOML written from the "
                             f"dict: {lines[int(found.group(1)) - 1]})") from None
        raise


def scene_replace(scene, changes):
    """A new prt.Scene: this one with `changes` ({section: {key: value}})
    merged in; a section given as None is removed. Relative paths still
    resolve against this scene's folder."""
    merged = scene_to_dict(scene)
    for section, body in changes.items():
        if body is None:
            merged.pop(section, None)
        elif isinstance(body, dict) and isinstance(merged.get(section), dict) and \
                "plugin" not in body:
            merged[section].update(body)
        else:
            merged[section] = body  # a new plug-in: its parameters start afresh
    return scene_from_dict(merged, base=pathlib.Path(scene.file).parent,
                           name=pathlib.Path(scene.file).stem + "-edited.toml")


def scene_to_dict(scene):
    """The scene's text as a dict (edit it and build another with from_dict)."""
    return tomllib.loads(scene.text)
