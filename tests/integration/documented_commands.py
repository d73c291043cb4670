#!/usr/bin/env python3
"""Every shell block of README.md and docs/*.md is accounted for, and runs.

Each ```sh block follows a marker that says what checks it:
  <!-- tested: integration.documented_commands -->  run here, verbatim, in order
      per document, in a scratch checkout that shares this build;
  <!-- tested: OTHER TEST ... -->   run verbatim by that test (its own script),
      or by CI (`tested: CI ...`);
  <!-- long: WHY -->                 minutes of work (a benchmark, a fresh
      build): the suite checks that every program it names exists and
      every `prt` subcommand is one `prt --help` lists; the ctest entry
      `docs.DOC:LINE` (label `long`, left out of scripts/test.sh) runs it;
  <!-- template: WHY -->             placeholders for the reader's own files:
      checked and run as `long` blocks are, with the stand-ins of
      tests/integration/doc_standins/DOC (no .md) copied into the checkout first;
  <!-- interactive: WHY -->          a window that runs until closed: checked as
      `long` blocks are; its `docs.DOC:LINE` entry runs it (under Xvfb without a
      display) and passes when it is still running, without an error, after
      INTERACTIVE_SECONDS without output (a viewer that bakes first prints
      its progress until the window opens).
A block without a marker fails the test, so a new command cannot go untried.

Long, template and interactive blocks run one ctest entry each, in order, in
one scratch checkout (build/docs-long/checkout, sharing this build) where the
`docs.setup` entry first ran README.md's first steps, and each block's own
page's run-here blocks above it run first, as a reader would. A
block that builds (scripts/demo.sh, scripts/build.sh) runs in a copy of the
tracked sources with a build of its own instead. Without a display every
long block runs under `xvfb-run -a`; as root, mpirun gets OpenMPI's
OMPI_ALLOW_RUN_AS_ROOT variables (the docs tell root readers to add
--allow-run-as-root).

  documented_commands.py <prt> <build folder> <source folder>   the suite's check
  documented_commands.py --list <source folder>                  DOC:LINE of each long block
  documented_commands.py --setup <prt> <build folder> <source folder>
  documented_commands.py --run DOC:LINE <prt> <build folder> <source folder>
"""
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time

MARKER = re.compile(r"<!--\s*(tested|long|template|interactive):\s*(.*?)\s*-->")
HERE = "integration.documented_commands"
RUN_LATER = ("long", "template", "interactive")
INTERACTIVE_SECONDS = int(os.environ.get("PRT_DOCS_QUIET_SECONDS", "20"))  # tests shorten it
BUILDS = re.compile(r"scripts/(demo|build)\.sh")


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


def documents(src):
    return ["README.md"] + sorted(os.path.join("docs", f) for f in os.listdir(
        os.path.join(src, "docs")) if f.endswith(".md"))


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
    skip = {"xvfb-run", "-a", "env", "time", "do", "then"}
    i = 0
    while i < len(words):
        w = words[i]
        if re.match(r"^[A-Za-z_][A-Za-z0-9_]*=", w) or w in skip:
            i += 1
        elif w == "mpirun":  # mpirun [--oversubscribe] [-np N] PROGRAM
            i += 1
            while i < len(words) and words[i].startswith("-"):
                i += 2 if words[i] in ("-np", "-n") else 1
        else:
            return words[i:]
    return []


def check_names(doc, line, text, prt, build, src, subcommands):
    problems = []
    shell_words = {"for", "done", "cd", "export", "mkdir", "sed", "cmake", "ctest", "echo",
                   "mpirun", "rm", "cp"}
    interpreters = {"/usr/bin/python3", "python3", "bash"}
    for command in commands(text):
        words = program_of(command)
        command = " ".join(command)
        interpreted = bool(words) and words[0] in interpreters
        if interpreted:  # the script it runs must exist, but need not be executable
            words = words[1:]
        if not words or words[0] in shell_words or words[0].startswith(("$", "-")):
            continue
        program = words[0].strip('"')
        if "$HOME/prt/bin/" in program:  # an install the block itself makes
            continue
        standin = os.path.join(standins_of(src, doc), program.split("/")[0])
        if "/" in program and os.path.islink(standin):  # OLD -> build: resolved in the checkout
            program = os.path.join(os.readlink(standin), program.split("/", 1)[1])
        if program.startswith("build/"):
            where = os.path.join(build, program[len("build/"):])
        else:
            where = os.path.join(src, program)
        if "/" in program and not os.path.exists(where):
            problems.append(f"{doc}:{line}: `{command}`: {program} does not exist")
        elif "/" in program and not interpreted and not os.access(where, os.X_OK):
            problems.append(f"{doc}:{line}: `{command}`: {program} is not executable")
        elif "/" not in program and not shutil.which(program):
            problems.append(f"{doc}:{line}: `{command}`: {program} is not installed")
        arguments = [w for w in words[1:] if w not in ("-q", "--quiet")]  # prt's flags
        if os.path.basename(program) == "prt" and arguments and not arguments[0].startswith("-"):
            if arguments[0] not in subcommands:
                problems.append(f"{doc}:{line}: `{command}`: prt has no subcommand {arguments[0]}")
    return problems


def standins_of(src, doc):
    """Files that stand in for a template block's "your own files"."""
    return os.path.join(src, "tests", "integration", "doc_standins",
                        os.path.splitext(os.path.basename(doc))[0])


def tracked_copy(src, to):
    """The source tree as a fresh clone has it: tracked files only (without
    git, or outside a checkout: everything but the top level's build folders,
    out/, data/ and .git)."""
    try:
        listed = subprocess.run(["git", "-C", src, "ls-files", "-z"], capture_output=True)
    except OSError:
        listed = None
    if listed is None or listed.returncode != 0:
        skip = lambda folder, names: [n for n in names if folder == src and (
            n.startswith("build") or n in ("out", "data", ".git"))]
        shutil.copytree(src, to, symlinks=True, ignore=skip)
        return
    for name in listed.stdout.decode().split("\0"):
        if not name or not os.path.lexists(os.path.join(src, name)):
            continue
        target = os.path.join(to, name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        if os.path.islink(os.path.join(src, name)):
            os.symlink(os.readlink(os.path.join(src, name)), target)
        elif os.path.isfile(os.path.join(src, name)):
            shutil.copy2(os.path.join(src, name), target)


def scratch_checkout(build, src, work):
    """A checkout in work/checkout that shares this build and data/."""
    checkout = os.path.join(work, "checkout")
    os.makedirs(os.path.join(work, "home"), exist_ok=True)
    tracked_copy(src, checkout)
    os.symlink(build, os.path.join(checkout, "build"))
    os.symlink(os.path.join(src, "data"), os.path.join(checkout, "data"))
    return checkout


def run_here_blocks(src, doc):
    return [(doc, line, text) for line, kind, why, text in blocks(os.path.join(src, doc))
            if kind == "tested" and why.startswith(HERE)]


def reader_env(work):
    """A reader's environment: a home of its own in work/; as root, what
    --allow-run-as-root says, for the docs' mpirun lines."""
    env = dict(os.environ, HOME=os.path.join(work, "home"))
    if os.getuid() == 0:
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    return env


def run_blocks(to_run, checkout, work):
    for doc, line, text in to_run:
        print(f"--- {doc}:{line}\n{text}")
        process = subprocess.Popen(["bash", "-euo", "pipefail", "-c", text], cwd=checkout,
                                   env=reader_env(work),
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                   start_new_session=True)
        try:
            output, _ = process.communicate(timeout=600)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)  # the block's programs too, not just bash
            process.communicate()
            print(f"FAIL {doc}:{line}: the block ran past 600 s")
            return False
        print("\n".join("    " + t for t in output.strip().split("\n")[-6:]))
        if process.returncode != 0:
            print(f"FAIL {doc}:{line}: the block exited with {process.returncode}")
            return False
    return True


def main(prt, build, src):
    build, src = os.path.realpath(build), os.path.realpath(src)
    help_text = subprocess.run([prt, "--help"], capture_output=True, text=True).stdout
    subcommands = set(re.findall(r"^\s{2}([a-z][a-z-]+)\s{2,}", help_text, re.M))
    problems, to_run, counts = [], [], {}
    for doc in documents(src):
        for line, kind, why, text in blocks(os.path.join(src, doc)):
            label = (kind or "unmarked") if kind != "tested" else ("run here" if why.startswith(HERE) else "run by " + why.split()[0])
            counts[label] = counts.get(label, 0) + 1
            if kind is None:
                problems.append(f"{doc}:{line}: a ```sh block without a <!-- tested | long | "
                                "template | interactive: ... --> marker")
            elif kind == "tested" and why.startswith(HERE):
                to_run.append((doc, line, text))
            elif kind != "tested":
                problems += check_names(doc, line, text, prt, build, src, subcommands)
    print("blocks: " + ", ".join(f"{n} {k}" for k, n in sorted(counts.items())))
    if problems:
        print("\n".join("FAIL " + p for p in problems))
        return 1
    work = tempfile.mkdtemp(prefix="prt-docs-")
    try:
        if not run_blocks(to_run, scratch_checkout(build, src, work), work):
            return 1
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"documented commands: {len(to_run)} blocks run verbatim, every other block's "
          "programs exist (ctest -L long runs them)")
    return 0


def list_long(src):
    """DOC:LINE of every block a `docs.DOC:LINE` ctest entry runs."""
    for doc in documents(src):
        for line, kind, why, text in blocks(os.path.join(src, doc)):
            if kind in RUN_LATER:
                print(f"{doc}:{line}")
    return 0


def long_work(build):
    return os.path.join(build, "docs-long")


def setup_long(prt, build, src):
    """A fresh scratch checkout where README.md's first steps have run."""
    build, src = os.path.realpath(build), os.path.realpath(src)
    work = long_work(build)
    shutil.rmtree(work, ignore_errors=True)
    checkout = scratch_checkout(build, src, work)
    return 0 if catch_up(src, "README.md", sys.maxsize, checkout, work) else 1


def catch_up(src, doc, line, checkout, work):
    """Runs the page's run-here blocks above this line that this checkout has
    not run yet: a reader follows a page in order (the room is baked before
    its sweep)."""
    done_file = os.path.join(work, "blocks-run")
    done = set(open(done_file).read().split()) if os.path.exists(done_file) else set()
    for block in run_here_blocks(src, doc):
        if block[1] < line and f"{doc}:{block[1]}" not in done:
            if not run_blocks([block], checkout, work):
                return False
            with open(done_file, "a") as log:
                log.write(f"{doc}:{block[1]}\n")
    return True


def shell(text):
    """bash running the block verbatim, under a virtual display when there is none."""
    command = ["bash", "-euo", "pipefail", "-c", text]
    if not os.environ.get("DISPLAY") and shutil.which("xvfb-run"):
        command = ["xvfb-run", "-a"] + command
    return command


def run_interactive(command, cwd, env):
    """Passes when the program is still running, with no error, once it has
    printed nothing for INTERACTIVE_SECONDS (a viewer that bakes first prints
    its progress until its window opens)."""
    with tempfile.NamedTemporaryFile() as log:
        process = subprocess.Popen(command, cwd=cwd, env=env, stdout=log,
                                   stderr=subprocess.STDOUT, start_new_session=True)
        size, quiet = -1, 0
        while process.poll() is None and quiet < INTERACTIVE_SECONDS:
            time.sleep(1)
            grown = os.path.getsize(log.name)
            quiet, size = (quiet + 1, size) if grown == size else (0, grown)
        running = process.poll() is None
        if running:
            os.killpg(process.pid, signal.SIGTERM)
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
        output = open(log.name, "rb").read().decode(errors="replace")
    print(output[-3000:])
    if not running:
        print(f"FAIL: it exited with {process.returncode}; an interactive program runs "
              "until closed")
        return 1
    if re.search(r"error:|terminate called|Segmentation fault|Aborted|Sanitizer", output):
        print("FAIL: it printed an error")
        return 1
    print(f"still running, quiet for {INTERACTIVE_SECONDS} s, no error: closed")
    return 0


def run_long(which, prt, build, src):
    """Runs one long, template or interactive block verbatim."""
    build, src = os.path.realpath(build), os.path.realpath(src)
    doc, line = which.rsplit(":", 1)
    found = [b for b in blocks(os.path.join(src, doc)) if b[0] == int(line)]
    if not found or found[0][1] not in RUN_LATER:
        print(f"FAIL {which}: no long, template or interactive block starts there "
              "(the docs changed since cmake ran: build again)")
        return 1
    _, kind, why, text = found[0]
    work = long_work(build)
    checkout = os.path.join(work, "checkout")
    env = reader_env(work)
    if BUILDS.search(text):  # a fresh tree of its own: the block builds
        checkout = os.path.join(work, "own-" + which.replace("/", "_").replace(":", "_"))
        shutil.rmtree(checkout, ignore_errors=True)
        tracked_copy(src, checkout)
    elif not os.path.isdir(checkout):
        print(f"FAIL {which}: no checkout at {checkout} (ctest runs docs.setup first)")
        return 1
    elif not catch_up(src, doc, int(line), checkout, work):
        return 1
    if kind == "template":
        standins = standins_of(src, doc)
        if not os.path.isdir(standins):
            print(f"FAIL {which}: a template block needs stand-ins in {standins}")
            return 1
        for name in os.listdir(standins):  # replaced, so a second run finds them as the first
            target = os.path.join(checkout, name)
            if os.path.islink(target) or os.path.isfile(target):
                os.remove(target)
            elif os.path.isdir(target):
                shutil.rmtree(target)
        shutil.copytree(standins, checkout, symlinks=True, dirs_exist_ok=True)
    print(f"--- {which} ({kind}: {why}) in {checkout}\n{text}\n---", flush=True)
    start = time.time()
    if kind == "interactive":
        return run_interactive(shell(text), checkout, env)
    status = subprocess.run(shell(text), cwd=checkout, env=env).returncode
    print(f"--- {which}: exit {status} after {time.time() - start:.0f} s")
    return 0 if status == 0 else 1


if __name__ == "__main__":
    if sys.argv[1:2] == ["--list"]:
        sys.exit(list_long(os.path.realpath(sys.argv[2])))
    if sys.argv[1:2] == ["--setup"]:
        sys.exit(setup_long(*sys.argv[2:5]))
    if sys.argv[1:2] == ["--run"]:
        sys.exit(run_long(*sys.argv[2:6]))
    sys.exit(main(*sys.argv[1:4]))
