#!/usr/bin/env python3
"""The bad-model corpus: files no bake should crash on, generated at test time and run through
drape-bake (and drape-inspect on what it writes). Run by the test command in the Release build and
again in the AddressSanitizer + UndefinedBehaviorSanitizer build.

  bad_model_corpus.py DRAPE_BAKE DRAPE_INSPECT SOURCE_DIR SHARED_DIR

The corpus, seeded (identical on every run):
  - an empty file and 256 random bytes under every extension drape-bake --formats lists;
  - each shared character (and the built-in mannequin) cut to a third and two thirds of its
    bytes, and three copies with 16 bytes flipped each;
  - headers that declare more than the file holds (OFF, PLY text and binary, B3D);
  - a Blitz3D character whose animation keys run past the clip's stated duration (loads, with a
    warning).
Every bake must end with exit 0 (and an asset drape-inspect reads) or exit 1 with one stderr line
naming the file and no output; never a signal, a sanitizer report or a hang.
"""

import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile

SANITIZER_MARKS = ("AddressSanitizer", "LeakSanitizer", "runtime error:", "UndefinedBehavior")
# Small maps and a short reader time limit keep the corpus quick under the sanitizers.
CONFIG = '{"import": {"time_limit_s": 60}, "maps": {"resolution": 128}}'


def b3d_column(duration_frames, key_frames):
    """A 1.6 m column on two bones whose rotation keys sit at key_frames (see import_repair_test)."""
    out = bytearray()
    stack = []

    def begin(tag):
        out.extend(tag)
        stack.append(len(out))
        out.extend(b"\0\0\0\0")

    def end():
        at = stack.pop()
        out[at:at + 4] = struct.pack("<I", len(out) - at - 4)

    def ints(*v):
        out.extend(struct.pack("<%di" % len(v), *v))

    def floats(*v):
        out.extend(struct.pack("<%df" % len(v), *v))

    def node(name, y):
        out.extend(name + b"\0")
        floats(0, y, 0, 1, 1, 1, 1, 0, 0, 0)

    def keys():
        begin(b"KEYS")
        ints(4)
        for f in key_frames:
            ints(f)
            floats(1, 0, 0, 0)
        end()

    begin(b"BB3D"), ints(1)
    begin(b"NODE"), node(b"root", 0)
    begin(b"MESH"), ints(-1)
    begin(b"VRTS"), ints(0, 0, 0)
    for y in (0.0, 0.8, 1.6):
        for k in range(4):
            floats(-0.15 if k in (0, 3) else 0.15, y, -0.1 if k < 2 else 0.1)
    end()
    begin(b"TRIS"), ints(-1)
    for ring in range(2):
        for k in range(4):
            a, b = ring * 4 + k, ring * 4 + (k + 1) % 4
            ints(a, b, b + 4, a, b + 4, a + 4)
    ints(0, 2, 1, 0, 3, 2, 8, 9, 10, 8, 10, 11)
    end(), end()
    begin(b"ANIM"), ints(0, duration_frames), floats(10), end()
    begin(b"NODE"), node(b"hips", 0.8)
    begin(b"BONE")
    for v in range(8):
        ints(v), floats(1)
    end()
    keys()
    begin(b"NODE"), node(b"chest", 0.4)
    begin(b"BONE")
    for v in range(8, 12):
        ints(v), floats(1)
    end()
    keys()
    end(), end(), end(), end()
    return bytes(out)


def corpus(bake, source, shared, work):
    """[(path, expectation)]: expectation is 'refused', 'loads' or 'either'."""
    rng = random.Random(20261127)
    files = []

    def write(name, data, expect):
        path = os.path.join(work, name)
        with open(path, "wb") as f:
            f.write(data)
        files.append((path, expect))

    extensions = subprocess.run([bake, "--formats"], capture_output=True, text=True,
                                check=True).stdout.split()
    for ext in extensions:
        write("empty" + ext, b"", "refused")
        write("noise" + ext, bytes(rng.getrandbits(8) for _ in range(256)), "refused")

    characters = [os.path.join(source, "samples", "mannequin", "mannequin.gltf")]
    root = os.path.join(shared, "assets", "characters")
    if os.path.isdir(root):
        for d in sorted(os.listdir(root)):
            for name in sorted(os.listdir(os.path.join(root, d))):
                if os.path.splitext(name)[1].lower() in (".glb", ".gltf", ".fbx", ".dae", ".x"):
                    characters.append(os.path.join(root, d, name))
    else:
        print(f"bad_model_corpus: {root} absent; the shared characters are left out")
    for path in characters:
        with open(path, "rb") as f:
            data = f.read()
        stem, ext = os.path.splitext(os.path.basename(path))
        for part in (3, 2):  # a third and two thirds
            write(f"{stem}_cut{part}{ext}", data[:len(data) * (3 - part) // 3 or 1], "refused")
        for copy in range(3):
            flipped = bytearray(data)
            for _ in range(16):
                flipped[rng.randrange(len(flipped))] ^= 0xFF
            write(f"{stem}_flip{copy}{ext}", bytes(flipped), "either")

    off = b"OFF\n3 353000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    write("huge_faces.off", off + b"\n" * (300 - len(off)), "refused")
    write("huge_counts.off", b"OFF\n100000000 100000000 0\n", "refused")
    write("huge_elements.ply", b"ply\nformat ascii 1.0\nelement vertex 4000000000\n"
          b"property float x\nend_header\n0\n", "refused")
    write("huge_list.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
          b"property float x\nproperty float y\nproperty float z\nelement face 1\n"
          b"property list int int vertex_index\nend_header\n" + b"\0" * 36 +
          struct.pack("<i", 0x7fffffff) + b"\0" * 12, "refused")
    column = b3d_column(20, list(range(1, 22)))
    tris = column.find(b"TRIS")
    write("huge_chunk.b3d", column[:tris + 4] + struct.pack("<I", 0xfffffff0) + column[tris + 8:],
          "refused")
    write("keys_past_duration.b3d", column, "loads")
    return files


def check(bake, inspect, path, expect, work):
    """'' when the bake behaved, else what went wrong."""
    out = path + ".drape"
    config = os.path.join(work, "corpus_config.json")
    try:
        run = subprocess.run([bake, path, "-o", out, "--config", config], capture_output=True,
                             text=True, errors="replace", timeout=240)
    except subprocess.TimeoutExpired:
        return "no answer within 240 s"
    stderr = run.stderr.strip()
    if any(mark in stderr for mark in SANITIZER_MARKS):
        return "sanitizer report:\n" + stderr[-3000:]
    if run.returncode < 0 or run.returncode not in (0, 1):
        return f"exit {run.returncode}: {stderr[-500:]}"
    if run.returncode == 1:
        if expect == "loads":
            return f"refused: {stderr}"
        lines = stderr.splitlines()
        if len(lines) != 1 or path not in lines[0]:
            return f"expected one stderr line naming the file, got: {stderr[-800:]}"
        if os.path.exists(out):
            return "an output file was left behind"
        return ""
    if expect == "refused":
        return "accepted"
    shown = subprocess.run([inspect, out], capture_output=True, text=True, errors="replace")
    if shown.returncode != 0:
        return f"drape-inspect refuses the asset: {shown.stderr.strip()}"
    if expect == "loads" and "warning:" not in stderr:
        return "no warning for the repaired file"
    return ""


def main():
    if len(sys.argv) != 5:
        print(__doc__)
        return 2
    bake, inspect, source, shared = sys.argv[1:]
    work = tempfile.mkdtemp(prefix="drape_corpus_")
    try:
        with open(os.path.join(work, "corpus_config.json"), "w") as f:
            f.write(CONFIG)
        files = corpus(bake, source, shared, work)
        failures = 0
        for path, expect in files:
            problem = check(bake, inspect, path, expect, work)
            if problem:
                failures += 1
                print(f"FAIL {os.path.basename(path)} ({expect}): {problem}")
        print(f"bad_model_corpus: {len(files) - failures} passed, {failures} failed "
              f"of {len(files)} files")
        return 1 if failures else 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
