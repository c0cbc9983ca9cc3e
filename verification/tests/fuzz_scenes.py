#!/usr/bin/env python3
"""A seeded scene and checkpoint fuzzer for `liquid run`.

    fuzz_scenes.py LIQUID SCENES_DIR [--cases N] [--checkpoints M] [--seed S] [--jobs J]
                   [--timeout T] [--keep DIR]

Scenes: N mutations of the built-in scene files (values replaced by 0, -1, NaN, inf, 1e308, huge
strings, wrong types and wrong-length vectors; lines deleted, duplicated or swapped; tables
duplicated; the file truncated), each run as `liquid run FILE --steps 2 --out D/o` in its own
folder D under a memory limit and a time limit. Checkpoints: M bit flips and truncations of a real
PIC and a real SPH checkpoint of two-step runs, each resumed from step 1.

A run passes when it exits 0; 1 with a message; or 2 with a message naming the scene file and a
line (FILE:LINE), or the file and a missing table or key -- for a checkpoint, naming the checkpoint. It fails on a signal, exit 3 (an
internal error), a hang past the time limit, an exit 2 that names no line, or a file written
outside its folder D (each run's D sits alone in a folder of its own, which must stay so). Every failing input is copied to --keep (default: fuzz-failures/) with the
command and its output, ready to become a catalogue entry. Exit 0 when every run passed.
"""
import argparse
import concurrent.futures
import os
import random
import re
import resource
import shutil
import subprocess
import sys
import tempfile

VALUES = ["0", "-1", "nan", "inf", "-inf", "1e308", "-1e308", "1e-308", "99999999999999999999",
          '""', '"' + "x" * 100000 + '"', "true", "[]", "[1.0]", "[1.0, 2.0, 3.0, 4.0]",
          '["a", "b"]', "{}", '"text"', "0.5", "2", "-0.0", "[nan, nan]", "[1e308, -1e308]"]
# Scenes whose own two steps take most of the time limit on one thread (the 3D dam break settles
# its column for 0.2 s first: 23 s; the 3D pour 7 s) run on a coarser lattice, 8x fewer particles.
COARSER = {"sph-dam-break-3d.toml": ["--spacing", "0.05"], "sph-pour-3d.toml": ["--spacing", "0.05"]}
KEY_LINE = re.compile(r"^\s*([A-Za-z0-9_.-]+)\s*=\s*(.*)$")


def mutate(text: str, rng: random.Random) -> str:
    lines = text.split("\n")
    keys = [i for i, line in enumerate(lines) if KEY_LINE.match(line)]
    kind = rng.choice(["value", "value", "value", "value", "delete", "duplicate", "swap", "table",
                       "truncate", "bytes"])
    if kind == "value" and keys:
        for _ in range(rng.choice([1, 1, 2, 3])):
            i = rng.choice(keys)
            key = KEY_LINE.match(lines[i]).group(1)
            lines[i] = f"{key} = {rng.choice(VALUES)}"
    elif kind == "delete" and lines:
        del lines[rng.randrange(len(lines))]
    elif kind == "duplicate" and lines:
        i = rng.randrange(len(lines))
        lines.insert(i, lines[i])
    elif kind == "swap" and len(lines) > 1:
        i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    elif kind == "table":
        heads = [i for i, line in enumerate(lines) if line.startswith("[")]
        if heads:
            i = rng.choice(heads)
            end = next((j for j in range(i + 1, len(lines)) if lines[j].startswith("[")), len(lines))
            block = lines[i:end]
            if rng.random() < 0.5:
                lines[i:end] = []  # the table deleted
            else:
                lines.extend(block)  # the table duplicated
    elif kind == "truncate":
        return text[: rng.randrange(len(text) + 1)]
    else:
        data = bytearray(text.encode())
        for _ in range(rng.randrange(1, 4)):
            data.insert(rng.randrange(len(data) + 1), rng.randrange(256))
        return data.decode("utf-8", errors="replace")
    return "\n".join(lines)


def limit_memory():
    gb = 8 << 30
    resource.setrlimit(resource.RLIMIT_AS, (gb, gb))


def judge(cmd, cwd, timeout, line_pattern):
    env = dict(os.environ, OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive")
    try:
        p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, errors="replace", timeout=timeout,
                           preexec_fn=limit_memory, env=env)
    except subprocess.TimeoutExpired:
        return f"hang: no exit within {timeout} s", ""
    out = p.stdout + p.stderr
    if p.returncode < 0:
        return f"signal {-p.returncode}", out
    if p.returncode == 0:
        return None, out
    if p.returncode == 1:
        return (None if "liquid:" in out else "exit 1 without a message"), out
    if p.returncode == 2:
        return (None if re.search(line_pattern, out) else "exit 2 naming no FILE:LINE"), out
    return f"exit {p.returncode}", out


def isolated(root, name):
    """root/NAME/work: the run's folder; root/NAME must hold nothing else afterwards."""
    outer = os.path.join(root, name)
    work = os.path.join(outer, "work")
    os.makedirs(work)
    return outer, work


def strays(outer):
    return sorted(set(os.listdir(outer)) - {"work"})


def run_scene_case(liquid, root, n, source, text, timeout):
    outer, work = isolated(root, f"case{n:04d}")
    scene = os.path.join(work, "scene.toml")
    with open(scene, "w", encoding="utf-8", errors="replace") as f:
        f.write(text)
    problem, out = judge([liquid, "run", scene, "--steps", "2", "--out", os.path.join(work, "o"),
                          *COARSER.get(source, [])], work, timeout,
                         r"scene\.toml(:\d+|: missing (table|key))")
    if strays(outer):
        problem = (problem + "; " if problem else "") + f"wrote outside its folder: {strays(outer)}"
    return n, source, scene, problem, out


def run_checkpoint_case(liquid, root, n, source, data, timeout):
    outer, work = isolated(root, f"checkpoint{n:04d}")
    path = os.path.join(work, "mutated_checkpoint.h5")
    with open(path, "wb") as f:
        f.write(data)
    problem, out = judge([liquid, "run", "--resume", path, "--out", os.path.join(work, "o")], work, timeout,
                         r"mutated_checkpoint\.h5")
    if strays(outer):
        problem = (problem + "; " if problem else "") + f"wrote outside its folder: {strays(outer)}"
    return n, source, path, problem, out


def real_checkpoints(liquid, root):
    """A PIC and an SPH checkpoint of small runs (their scene files stay where they are)."""
    made = []
    for scene, extra in (("pool-2d", []), ("sph-dam-break-2d", ["--spacing", "0.04"])):
        out = os.path.join(root, "seed-" + scene)
        subprocess.run([liquid, "run", scene, "--steps", "2", "--checkpoint-every", "1", "--out", out,
                        "--quiet", *extra], check=True, capture_output=True)
        made.append(os.path.join(out, f"{scene}_checkpoint_000001.h5"))
    return made


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("liquid")
    ap.add_argument("scenes")
    ap.add_argument("--cases", type=int, default=300)
    ap.add_argument("--checkpoints", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--keep", default="fuzz-failures")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    sources = sorted(f for f in os.listdir(a.scenes) if f.endswith(".toml"))
    texts = {s: open(os.path.join(a.scenes, s)).read() for s in sources}
    root = tempfile.mkdtemp(prefix="fuzz-")
    failures = []
    try:
        checkpoints = real_checkpoints(a.liquid, root)
        blobs = {c: open(c, "rb").read() for c in checkpoints}
        with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
            jobs = []
            for n in range(a.cases):
                source = rng.choice(sources)
                jobs.append(pool.submit(run_scene_case, a.liquid, root, n, source, mutate(texts[source], rng),
                                        a.timeout))
            for n in range(a.checkpoints):
                source = rng.choice(checkpoints)
                data = bytearray(blobs[source])
                if rng.random() < 0.3:
                    data = data[: rng.randrange(len(data))]
                else:
                    for _ in range(rng.randrange(1, 9)):
                        i = rng.randrange(len(data))
                        data[i] ^= 1 << rng.randrange(8)
                jobs.append(pool.submit(run_checkpoint_case, a.liquid, root, n, os.path.basename(source),
                                        bytes(data), a.timeout))
            for job in concurrent.futures.as_completed(jobs):
                n, source, path, problem, out = job.result()
                if problem:
                    failures.append((n, source, path, problem, out))
        for n, source, path, problem, out in sorted(failures, key=lambda f: f[2]):
            os.makedirs(a.keep, exist_ok=True)
            kept = os.path.join(a.keep, os.path.basename(os.path.dirname(os.path.dirname(path))) + "-" +
                                os.path.basename(path))
            shutil.copy(path, kept)
            with open(kept + ".log", "w") as f:
                f.write(f"from {source}: {problem}\n{out}")
            tail = out.strip().splitlines()[-1:] if out.strip() else [""]
            print(f"FAILED: {os.path.basename(kept)} (from {source}): {problem}: {tail[0][:300]}")
    finally:
        shutil.rmtree(root, ignore_errors=True)
    total = a.cases + a.checkpoints
    print(f"fuzz_scenes.py: {total - len(failures)} of {total} inputs handled ({a.cases} scenes from "
          f"{len(sources)} files, {a.checkpoints} checkpoints; seed {a.seed})")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
