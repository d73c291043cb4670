#!/usr/bin/python3
"""Crafted bake files against prt: mutations of a small bake, each sealed with
a valid length and CRC-32 (as someone who crafts a file on purpose would),
given to `prt info`, `prt render` and `prt compress`.

    /usr/bin/python3 scripts/crafted_bakes.py [--count 10000] [--seed 1] [--jobs 2]

Mutations: bit flips, byte runs (random, 0x00 or 0xff) and truncations, half
of them in the first 8 KB of the HDF5 part, where its metadata starts. Every
run must end in exit 0 or in a refusal (exit 1, one line "prt: ..." naming
the bake or the scene), within --timeout seconds, under --rss-limit of peak
resident memory (the command and the process it parses the file in), and
leave no output or temporary behind when it refuses. Inputs that break a
rule are kept in --keep. Prints a summary; exits 1 when a rule is broken.
"""
import argparse
import concurrent.futures
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import zlib

BLOCK = 512
SCENE = """[mesh]
generate = "sphere"
detail = 3
[lighting]
constant = [1, 1, 1]
[basis]
plugin = "sh"
order = 3
[transport]
rays = 32
[compressor]
plugin = "cpca"
clusters = 4
components = 2
[camera]
width = 32
height = 32
"""


def seal(data: bytearray, version: int) -> bytes:
    body = bytes(data[BLOCK:])
    header = ("PRT-BAKE\nformat %d\nlength %d\ncrc32 %08x\n"
              "(a PRT bake file: HDF5 after this %d-byte block)\n" %
              (version, len(data), zlib.crc32(body) & 0xFFFFFFFF, BLOCK)).encode()
    return header.ljust(BLOCK, b"\0") + body


def mutate(original: bytes, rng: random.Random) -> tuple[str, bytearray]:
    data = bytearray(original)
    size = len(data)

    def position() -> int:
        if rng.random() < 0.5:
            return rng.randrange(BLOCK, min(size, BLOCK + 8192))
        return rng.randrange(BLOCK, size)

    kind = rng.choice(["flip", "run", "cut"])
    if kind == "flip":
        for _ in range(rng.randint(1, 3)):
            at = position()
            data[at] ^= 1 << rng.randrange(8)
    elif kind == "run":
        at, length = position(), rng.randint(1, 64)
        fill = rng.choice(["random", 0x00, 0xFF])
        for i in range(at, min(size, at + length)):
            data[i] = rng.randrange(256) if fill == "random" else fill
    else:
        del data[rng.randrange(BLOCK, size):]
    return kind, data


def run(command: list[str], timeout: float) -> tuple[int, str, float, bool]:
    """Exit code (negative: signal), stderr, peak RSS in bytes of the command
    and the children it waited for, whether it was killed at the timeout."""
    with tempfile.TemporaryFile() as err:
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=err)
        timed_out = threading.Event()

        def kill():
            timed_out.set()
            process.kill()

        timer = threading.Timer(timeout, kill)
        timer.start()
        _, status, usage = os.wait4(process.pid, 0)
        timer.cancel()
        process.returncode = (-os.WTERMSIG(status) if os.WIFSIGNALED(status)
                              else os.WEXITSTATUS(status))
        err.seek(0)
        text = err.read().decode("utf-8", "replace")
    return process.returncode, text, usage.ru_maxrss * 1024.0, timed_out.is_set()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser.add_argument("--prt", default=os.path.join(root, "build", "bin", "prt"))
    parser.add_argument("--count", type=int, default=10000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    parser.add_argument("--timeout", type=float, default=60)
    parser.add_argument("--rss-limit", type=float, default=1e9, help="bytes")
    parser.add_argument("--keep", default=os.path.join(root, "build", "crafted-bakes"))
    parser.add_argument("--commands", default="info,render,compress")
    args = parser.parse_args()

    work = tempfile.mkdtemp(prefix="prt-crafted-")
    scene = os.path.join(work, "scene.toml")
    with open(scene, "w") as f:
        f.write(SCENE)
    good = os.path.join(work, "good.h5")
    subprocess.run([args.prt, "-q", "bake", scene, "-o", good], check=True,
                   stdout=subprocess.DEVNULL)
    original = open(good, "rb").read()
    version = int(re.search(rb"format (\d+)", original[:BLOCK]).group(1))
    print(f"crafted bakes: {args.count} mutations of a {len(original):,}-byte bake "
          f"(seed {args.seed}), commands {args.commands}, {args.jobs} at a time")

    commands = args.commands.split(",")
    tally = {c: {"accepted": 0, "refused": 0} for c in commands}
    kinds = {"flip": 0, "run": 0, "cut": 0}
    broken = []  # (index, command, what)
    contained = {}  # index -> how the parsing process ended (it would have ended prt)
    peak = [0.0, ""]
    lock = threading.Lock()

    def one(index: int) -> None:
        rng = random.Random(args.seed * 1_000_003 + index)
        kind, data = mutate(original, rng)
        folder = os.path.join(work, str(index))  # its own, so temporaries are its own
        os.mkdir(folder)
        bake = os.path.join(folder, f"m{index}.h5")
        with open(bake, "wb") as f:
            f.write(seal(data, version))
        for name in commands:
            out = os.path.join(folder, name + (".png" if name == "render" else ".h5"))
            argv = {"info": [args.prt, "-q", "info", bake],
                    "render": [args.prt, "-q", "render", scene, "--bake", bake, "-o", out],
                    "compress": [args.prt, "-q", "compress", bake, "-c", "pca", "-p",
                                 "components=2", "-o", out]}[name]
            code, err, rss, timed_out = run(argv, args.timeout)
            lines = [line for line in err.splitlines() if line.strip()]
            problem = None
            if timed_out:
                problem = f"no answer within {args.timeout:g} s"
            elif code < 0:
                problem = f"signal {-code}"
            elif code not in (0, 1):
                problem = f"exit {code}"
            elif code == 1 and (len(lines) != 1 or not lines[0].startswith("prt: ") or
                                (bake not in lines[0] and scene not in lines[0])):
                problem = f"refusal not one located line: {err.strip()[:300]!r}"
            elif code == 1 and os.path.exists(out):
                problem = "refused but left its output"
            if rss > args.rss_limit:
                problem = (problem + "; " if problem else "") + f"peak RSS {rss / 1e6:.0f} MB"
            leftovers = [n for n in os.listdir(folder) if ".tmp-" in n]
            ended = re.search(r"killed by signal \d+ \([^)]*\)|more than \d+ s of processor time",
                              err)
            with lock:
                kinds[kind] += 1 if name == commands[0] else 0
                if rss > peak[0]:
                    peak[0], peak[1] = rss, name
                if problem:
                    broken.append((index, name, problem))
                    os.makedirs(args.keep, exist_ok=True)
                    shutil.copy(bake, os.path.join(args.keep, f"seed{args.seed}-m{index}.h5"))
                else:
                    tally[name]["accepted" if code == 0 else "refused"] += 1
                if ended and index not in contained:
                    contained[index] = ended.group(0)
                    os.makedirs(os.path.join(args.keep, "contained"), exist_ok=True)
                    shutil.copy(bake, os.path.join(args.keep, "contained", f"seed{args.seed}-m{index}.h5"))
                if leftovers and not timed_out:
                    broken.append((index, name, f"temporaries left: {leftovers}"))
            if os.path.exists(out):
                os.remove(out)
        shutil.rmtree(folder)

    started = time.time()
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        for future in concurrent.futures.as_completed(pool.submit(one, i)
                                                      for i in range(args.count)):
            future.result()
    seconds = time.time() - started
    shutil.rmtree(work, ignore_errors=True)

    print(f"mutations: {kinds['flip']} bit flips, {kinds['run']} byte runs, "
          f"{kinds['cut']} truncations; {seconds:.0f} s")
    for name in commands:
        t = tally[name]
        print(f"  prt {name:<9} accepted {t['accepted']:>6}  refused in one line {t['refused']:>6}")
    print(f"peak RSS: {peak[0] / 1e6:.0f} MB (prt {peak[1]}, with the process that parsed the file)")
    print(f"contained: {len(contained)} inputs ended the process that parsed them "
          f"(kept in {os.path.join(args.keep, 'contained')})")
    for index, how in sorted(contained.items())[:10]:
        print(f"  m{index}.h5: {how}")
    signals = sum(1 for b in broken if b[2].startswith("signal"))
    hangs = sum(1 for b in broken if b[2].startswith("no answer"))
    print(f"signals: {signals}, hangs: {hangs}, other broken rules: {len(broken) - signals - hangs}")
    for index, name, what in broken[:20]:
        print(f"  m{index}.h5, prt {name}: {what}")
    if broken:
        print(f"inputs kept in {args.keep}")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
