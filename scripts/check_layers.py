#!/usr/bin/env python3
"""Checks the include layers that docs/architecture.md states.

The page's ```layers block lists, lowest first, each layer's framework files
(header and source stems: "transfer" is prt/transfer.hpp and
framework/src/transfer.cpp) and folders (a path ending in "/"):
  RANK NAME [(RANKS)]: STEMS FOLDERS/
A file may include files of its own layer and of lower ones (only those in
RANKS when given, e.g. "(1-3)"); an include of a higher layer is a back-up
include, one of a lower layer that RANKS leaves out a skipped-layer include.
Each is printed with its file and line, and the script fails.

Also prints the longest chain of includes among the framework's files (its
floors). Standard library only: any python3.
  scripts/check_layers.py [--root DIR]
"""
import argparse
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')
SOURCES = (".hpp", ".cpp", ".h", ".c")


def read_layers(page):
    """[(rank, name, stems, folders, allowed ranks or None)] from the page's ```layers block."""
    text = open(page, encoding="utf-8").read()
    block = re.search(r"```layers\n(.*?)```", text, re.S)
    if not block:
        sys.exit(f"{page}: no ```layers block")
    layers = []
    for number, line in enumerate(block.group(1).splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        head, _, names = line.partition(":")
        rank, _, name = head.strip().partition(" ")
        allowed = None
        if "(" in name:
            name, _, ranks = name.partition("(")
            allowed = set()
            for part in ranks.rstrip(")").split(","):
                low, _, high = part.partition("-")
                allowed.update(range(int(low), int(high or low) + 1))
            allowed.add(int(rank))
        entries = names.split()
        layers.append((int(rank), name.strip(),
                       {e for e in entries if not e.endswith("/")},
                       [e for e in entries if e.endswith("/")], allowed))
    return layers


def layer_of(path, layers):
    """The layer (index) of a repository-relative path, or None."""
    stem, ext = os.path.splitext(os.path.basename(path))
    if path.startswith("framework/"):
        for index, (_, _, stems, _, _) in enumerate(layers):
            if stem in stems:
                return index
        return None
    best, best_length = None, -1
    for index, (_, _, _, folders, _) in enumerate(layers):
        for folder in folders:
            if path.startswith(folder) and len(folder) > best_length:
                best, best_length = index, len(folder)
    return best


def resolve(including, name, root):
    """The repository-relative file an include names (None: not ours)."""
    local = os.path.normpath(os.path.join(os.path.dirname(including), name))
    if os.path.isfile(os.path.join(root, local)):
        return local
    if name.startswith("prt/"):
        for base in ("framework/include", "plugins/compressor/clustering/include"):
            candidate = os.path.join(base, name)
            if os.path.isfile(os.path.join(root, candidate)):
                return candidate
    if os.path.isfile(os.path.join(root, "framework/src", name)):
        return os.path.join("framework/src", name)
    return None


def sources(root):
    for top in ("framework", "plugins", "apps", "python", "conformance", "gl"):
        for folder, _, files in os.walk(os.path.join(root, top)):
            for name in sorted(files):
                if name.endswith(SOURCES):
                    yield os.path.relpath(os.path.join(folder, name), root)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(__file__), ".."))
    root = os.path.abspath(parser.parse_args().root)
    layers = read_layers(os.path.join(root, "docs/architecture.md"))
    problems, graph = [], {}
    for path in sources(root):
        mine = layer_of(path, layers)
        if mine is None:
            problems.append(f"{path}: in no layer of docs/architecture.md")
            continue
        with open(os.path.join(root, path), encoding="utf-8", errors="replace") as source:
            for number, line in enumerate(source, 1):
                match = INCLUDE.match(line)
                if not match:
                    continue
                target = resolve(path, match.group(1), root)
                if target is None:
                    continue
                theirs = layer_of(target, layers)
                if theirs is None:
                    problems.append(f"{target}: in no layer of docs/architecture.md")
                    continue
                if path.startswith("framework/") and target.startswith("framework/"):
                    graph.setdefault(path, set()).add(target)
                allowed = layers[mine][4]
                if theirs > mine:
                    problems.append(
                        f"{path}:{number}: back-up include: layer {layers[mine][1]} "
                        f"includes {match.group(1)} (layer {layers[theirs][1]})")
                elif allowed is not None and layers[theirs][0] not in allowed:
                    problems.append(
                        f"{path}:{number}: skipped-layer include: layer {layers[mine][1]} "
                        f"includes {match.group(1)} (layer {layers[theirs][1]}), "
                        f"not one it may use")
    floors = {}

    def depth(node, seen=()):
        if node in floors:
            return floors[node]
        if node in seen:
            return 0
        floors[node] = 1 + max((depth(n, seen + (node,)) for n in graph.get(node, ())), default=0)
        return floors[node]

    deepest = max((depth(n) for n in graph), default=0)
    for problem in sorted(set(problems)):
        print(problem)
    backups = sum("back-up include" in p for p in set(problems))
    skipped = sum("skipped-layer include" in p for p in set(problems))
    print(f"check_layers: {len(layers)} layers, {backups} back-up includes, "
          f"{skipped} skipped-layer includes, "
          f"{len(set(problems)) - backups - skipped} files in no layer, "
          f"longest include chain {deepest} files")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
