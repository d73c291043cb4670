#!/usr/bin/env python3
"""Every shell block of README.md and docs/*.md is accounted for.

Each ```sh block follows a marker that says what checks it:
  <!-- tested: integration.documented_commands -->  run here, verbatim, in order
      per document, in a scratch checkout that shares this build;
  <!-- tested: OTHER TEST ... -->   run verbatim by that test (its own script);
  <!-- long: WHY -->                 minutes of work (a benchmark, the suite
      itself): every program it names must exist and every `prt` subcommand
      must be one `prt --help` lists;
  <!-- template: WHY -->             placeholders for the reader's own files:
      checked as `long` blocks are.
A block without a marker fails the test, so a new command cannot go untried.

  documented_commands.py <prt> <build folder> <source folder>
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

MARKER = re.compile(r"<!--\s*(tested|long|template):\s*(.*?)\s*-->")
HERE = "integration.documented_commands"


def blocks(path):
    """(line, kind, why, text) of each ```sh block, kind None when unmarked."""
    lines = open(path, encoding="utf-8").read().split("\n")
    found, marker, inside, start, body = [], None, False, 0, []
    for number, line in enumerate(lines, 1):
        if inside:
            if line.strip() == "```":
                found.append((start, marker[0] if marker else None,
                              marker[1] if marker else "", "\n".join(body)))
                inside, marker, body = False, None, []
            else:
                body.append(line)
            continue
        m = MARKER.search(line)
        if m:
            marker = (m.group(1), m.group(2))
        elif line.strip() == "```sh":
            inside, start = True, number
        elif line.strip():
            marker = None if not line.startswith("<!--") else marker
    return found


def commands(text):
    """The words of each command of a block: continuations joined, comments
    dropped, split at |, &&, || and ; outside quotes."""
    joined = re.sub(r"\\\n\s*", " ", text)
    for line in joined.split("\n"):
        lexer = shlex.shlex(line, posix=True, punctuation_chars=";&|")
        lexer.whitespace_split = True
        lexer.commenters = "#"
        try:
            tokens = list(lexer)
        except ValueError:
            tokens = line.split()
        words = []
        for token in tokens + [";"]:
            if token and set(token) <= set(";&|"):
                if words:
                    yield words
                words = []
            else:
                words.append(token)


def program_of(words):
    """The program a command runs, past VAR=value, env wrappers and shell words."""
    skip = {"xvfb-run", "-a", "env", "bash", "time", "do", "then"}
    i = 0
    while i < len(words):
        w = words[i]
        if re.match(r"^[A-Za-z_][A-Za-z0-9_]*=", w) or w in skip:
            i += 1
        elif w == "mpirun":  # mpirun [--oversubscribe] -np N PROGRAM
            i += 1
            while i < len(words) and words[i].startswith("-"):
                i += 2 if words[i] in ("-np", "-n") else 1
        else:
            return words[i:]
    return []


def check_names(doc, line, text, prt, build, src, subcommands):
    problems = []
    shell_words = {"for", "done", "cd", "export", "mkdir", "sed", "cmake", "ctest", "echo",
                   "/usr/bin/python3", "python3", "mpirun", "rm", "cp"}
    for command in commands(text):
        words = program_of(command)
        command = " ".join(command)
        if not words or words[0] in shell_words or words[0].startswith("$"):
            continue
        program = words[0].strip('"')
        if "$HOME/prt/bin/" in program:  # an install the block itself makes
            continue
        if program.startswith("build/"):
            where = os.path.join(build, program[len("build/"):])
        else:
            where = os.path.join(src, program)
        if "/" in program and not os.path.exists(where):
            problems.append(f"{doc}:{line}: `{command}`: {program} does not exist")
        elif "/" not in program and not shutil.which(program):
            problems.append(f"{doc}:{line}: `{command}`: {program} is not installed")
        if os.path.basename(program) == "prt" and len(words) > 1 and not words[1].startswith("-"):
            if words[1] not in subcommands:
                problems.append(f"{doc}:{line}: `{command}`: prt has no subcommand {words[1]}")
    return problems


def scratch_checkout(build, src):
    work = tempfile.mkdtemp(prefix="prt-docs-")
    checkout = os.path.join(work, "checkout")
    os.makedirs(os.path.join(work, "home"))
    os.makedirs(checkout)
    os.symlink(build, os.path.join(checkout, "build"))
    for folder in ("scenes", "examples", "scripts"):
        shutil.copytree(os.path.join(src, folder), os.path.join(checkout, folder), symlinks=True)
    os.symlink(os.path.join(src, "data"), os.path.join(checkout, "data"))
    return work, checkout


def main(prt, build, src):
    build, src = os.path.realpath(build), os.path.realpath(src)
    help_text = subprocess.run([prt, "--help"], capture_output=True, text=True).stdout
    subcommands = set(re.findall(r"^\s{2}([a-z][a-z-]+)\s{2,}", help_text, re.M))
    docs = ["README.md"] + sorted(os.path.join("docs", f) for f in os.listdir(
        os.path.join(src, "docs")) if f.endswith(".md"))
    problems, to_run, counts = [], [], {}
    for doc in docs:
        for line, kind, why, text in blocks(os.path.join(src, doc)):
            label = (kind or "unmarked") if kind != "tested" else ("run here" if why.startswith(HERE) else "run by " + why.split()[0])
            counts[label] = counts.get(label, 0) + 1
            if kind is None:
                problems.append(f"{doc}:{line}: a ```sh block without a <!-- tested | long | "
                                "template: ... --> marker")
            elif kind == "tested" and why.startswith(HERE):
                to_run.append((doc, line, text))
            elif kind != "tested":
                problems += check_names(doc, line, text, prt, build, src, subcommands)
    print("blocks: " + ", ".join(f"{n} {k}" for k, n in sorted(counts.items())))
    if problems:
        print("\n".join("FAIL " + p for p in problems))
        return 1
    work, checkout = scratch_checkout(build, src)
    try:
        for doc, line, text in to_run:
            print(f"--- {doc}:{line}\n{text}")
            run = subprocess.run(["bash", "-euo", "pipefail", "-c", text], cwd=checkout,
                                 env=dict(os.environ, HOME=os.path.join(work, "home")),
                                 capture_output=True, text=True, timeout=600)
            tail = (run.stdout + run.stderr).strip().split("\n")[-6:]
            print("\n".join("    " + t for t in tail))
            if run.returncode != 0:
                print(f"FAIL {doc}:{line}: the block exited with {run.returncode}")
                return 1
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"documented commands: {len(to_run)} blocks run verbatim, every other block's "
          "programs exist")
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
