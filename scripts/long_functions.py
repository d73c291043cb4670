#!/usr/bin/env python3
"""Lists the C++ functions longer than a limit, longest first.

A function is a brace block opened at namespace or class level after a
closing parenthesis (with optional qualifiers: const, noexcept, override,
a trailing return type or a constructor's initialiser list); its length is
the lines from its signature's first line to its closing brace. Lambdas and
blocks inside count toward the function that holds them. Comments, strings
and preprocessor lines are skipped. Standard library only.
  scripts/long_functions.py [--over N] [--root DIR] [FOLDER ...]
"""
import argparse
import os
import re
import sys

FOLDERS = ("framework", "plugins", "apps", "python/src", "conformance", "gl")


def strip(text):
    """The text with comments, strings and characters blanked (lines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i)); i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif c == 'R' and text.startswith('R"', i):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c); i += 1; continue
            end = ")" + m.group(1) + '"'
            j = text.find(end, i + m.end())
            j = n if j < 0 else j + len(end)
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (j - i - 1) + (c if j < n else "")); i = j + 1
        else:
            out.append(c); i += 1
    return "".join(out)


def functions(path):
    text = strip(open(path, encoding="utf-8", errors="replace").read())
    text = "\n".join("" if l.lstrip().startswith("#") else l for l in text.split("\n"))
    stack, found, last = [], [], 0  # stack: (kind, start line)
    statement_start = 0
    for i, c in enumerate(text):
        if c in ";}":
            statement_start = i + 1
        if c == "{":
            head = text[statement_start:i]
            in_function = any(entry[0] == "function" for entry in stack)
            kind = "block"
            if not in_function:
                h = re.sub(r"\s+", " ", head).strip()
                if re.search(r"\)\s*(const|noexcept|override|final|mutable|->[^{]*|:\s*[^{]*|\s)*$", h) \
                        and not re.match(r"^(if|for|while|switch|catch|namespace|struct|class|enum|union)\b", h) \
                        and "=" not in h.split("(")[0]:
                    kind = "function"
            line = text.count("\n", 0, statement_start) + 1
            # the signature starts at the first non-blank line of the head
            offset = len(head) - len(head.lstrip())
            line = text.count("\n", 0, statement_start + offset) + 1
            name = re.sub(r"\s+", " ", head).strip()
            stack.append((kind, line, name))
            statement_start = i + 1
        elif c == "}" and stack:
            kind, line, name = stack.pop()
            if kind == "function":
                end = text.count("\n", 0, i) + 1
                found.append((end - line + 1, line, name))
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--over", type=int, default=60)
    parser.add_argument("--root", default=os.path.join(os.path.dirname(__file__), ".."))
    parser.add_argument("folders", nargs="*", default=FOLDERS)
    args = parser.parse_args()
    root = os.path.abspath(args.root)
    rows = []
    for folder in args.folders:
        for base, _, files in os.walk(os.path.join(root, folder)):
            for name in files:
                if name.endswith((".cpp", ".hpp", ".h")):
                    path = os.path.join(base, name)
                    for length, line, signature in functions(path):
                        if length > args.over:
                            short = signature.split("(")[0].split()[-1] if "(" in signature else signature
                            rows.append((length, f"{os.path.relpath(path, root)}:{line}", short))
    for length, where, name in sorted(rows, reverse=True):
        print(f"{length:5d}  {where}  {name}")
    print(f"long_functions: {len(rows)} functions over {args.over} lines")


if __name__ == "__main__":
    sys.exit(main())
