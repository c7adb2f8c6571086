#!/usr/bin/env python3
"""Hostile input through the whole `deform` CLI: one recipe per class of failure a campaign of mutated and crafted
files found (docs/reliability.md), scaled to run in seconds. For each, the promise: exit 0 or 2, never a signal or a
hang; exit 2 names the file; nothing non-finite is written or printed; memory stays within a stated multiple of the
input; no file is written that the user did not name, and what the user named keeps its kind and mode.
Usage: hostile_inputs_test.py DEFORM WORK_DIR SANITIZED(0|1) IMPORT(0|1)"""
import json, os, re, shutil, stat, struct, subprocess, sys, time

deform, work = os.path.abspath(sys.argv[1]), sys.argv[2]
sanitized, importer = sys.argv[3] == "1", sys.argv[4] == "1"
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []
# Sanitizers slow everything down and reserve shadow memory: their pass checks time loosely and memory not at all.
time_limit = 120 if sanitized else 30


def check(condition, message):
    if not condition:
        failures.append(message)


class Run:
    def __init__(self, code, out, err, seconds, peak_bytes):
        self.code, self.out, self.err, self.seconds, self.peak_bytes = code, out, err, seconds, peak_bytes


def run(*args, stdin=None):
    """Runs deform with ARGS; returns its exit code (negative: the signal), output, time and peak resident memory."""
    out_path, err_path = os.path.join(work, ".stdout"), os.path.join(work, ".stderr")
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        start = time.monotonic()
        p = subprocess.Popen([deform, *args], stdout=out, stderr=err, stdin=stdin or subprocess.DEVNULL, cwd=work)
        deadline = start + time_limit
        while True:
            pid, status, usage = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() > deadline:
                p.kill()
                pid, status, usage = os.wait4(p.pid, 0)
                failures.append(f"deform {' '.join(a[:60] for a in args)}: still running after {time_limit} s")
                break
            time.sleep(0.01)
        seconds = time.monotonic() - start
    code = os.waitstatus_to_exitcode(status)
    with open(out_path, "rb") as f:
        stdout = f.read().decode("utf-8", "replace")
    with open(err_path, "rb") as f:
        stderr = f.read().decode("utf-8", "replace")
    os.remove(out_path)
    os.remove(err_path)
    return Run(code, stdout, stderr, seconds, usage.ru_maxrss * 1024)


def path(name):
    return os.path.join(work, name)


def write(name, data):
    with open(path(name), "wb" if isinstance(data, bytes) else "w") as f:
        f.write(data)
    return path(name)


def expect(label, result, codes=(0, 2), names=None, max_bytes=None):
    print(f"{label}: exit {result.code}, {result.seconds:.2f} s, {result.peak_bytes >> 20} MiB")
    check(result.code in codes, f"{label}: exit {result.code} (expected {codes}): {result.err[-400:]}")
    if result.code == 2 and names is not None:
        check(names in result.err, f"{label}: the error does not name {names}: {result.err[:300]}")
    for text in (result.out, result.err):
        bad = NON_FINITE.search(text)
        check(bad is None, f"{label}: printed {bad and bad.group(0)!r}: {text[:200]}")
    if max_bytes is not None and not sanitized:
        check(result.peak_bytes <= max_bytes,
              f"{label}: peak memory {result.peak_bytes >> 20} MiB, more than {max_bytes >> 20} MiB")


def no_strays(label):
    strays = [n for n in os.listdir(work) if ".deform-tmp" in n]
    check(not strays, f"{label}: temporary files left behind: {strays}")


NON_FINITE = re.compile(r"(?<![A-Za-z_])[-+]?(nan|inf|infinity)(?![A-Za-z_])", re.IGNORECASE)
BASE = 64 << 20  # the CLI's own resident memory and this script's (a child's peak starts from its parent's)


def sk(name, count, translation):
    """A .sk chain of COUNT bones (docs/formats.md), each at TRANSLATION from its parent, limits ±180°."""
    parts = [b"SKEL" + struct.pack("<i", count)]
    for i in range(count):
        children = [i + 1] if i + 1 < count else []
        parts.append(f"bone{i}".encode().ljust(80, b"\0") + struct.pack("<6f", *translation, 0, 0, 0) +
                     struct.pack("<6f", 180, -180, 180, -180, 180, -180) +
                     struct.pack("<ii", i - 1, len(children)) + struct.pack("<%di" % len(children), *children))
    return write(name, b"".join(parts))


def skw(name, lines):
    return write(name, f"skw 1\nvertices {len(lines)}\n" + "".join(f"{i} {line}\n" for i, line in enumerate(lines)))


sk("two.sk", 2, (0, 1, 0))

# --- OBJ: quadratic work and memory (each recipe alone, without skeleton: `deform info`) ---
# one point used with 200,000 texture coordinates (the render-vertex search)
n = 200_000
obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\n" + "".join(f"vt {i / n} 0\n" for i in range(n))
obj += "".join(f"f 1/{i + 1} 2/1 3/1\n" for i in range(n))
r = run("info", write("many_vt.obj", obj))
expect("one point with 200,000 vt", r, codes=(0,), max_bytes=BASE + 30 * len(obj))

# one face of 300,000 corners on one point
obj = "v 0 0 0\nf" + " 1" * 300_000 + "\n"
r = run("info", write("wide_face.obj", obj))
expect("a face of 300,000 corners", r, codes=(0, 2), names="wide_face.obj", max_bytes=BASE + 14 * len(obj))

# a 20 MB one-face line: memory a stated multiple of the file (docs/reliability.md: about 16x), written in pieces so
# that this script's own memory (which a child's peak includes on Linux) stays small
with open(path("long_line.obj"), "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf")
    for _ in range(35):
        f.write(" 1 2 3" * 100_000)
    f.write("\n")
size = os.path.getsize(path("long_line.obj"))
r = run("info", path("long_line.obj"))
expect("a 20 MB one-face line", r, codes=(0, 2), names="long_line.obj", max_bytes=BASE + 17 * size)
os.remove(path("long_line.obj"))

# 64 MiB of NUL bytes
with open(path("nul.obj"), "wb") as f:
    for _ in range(64):
        f.write(b"\0" * (1 << 20))
r = run("info", path("nul.obj"))
expect("64 MiB of NUL", r, codes=(0, 2), names="nul.obj", max_bytes=BASE + 2 * (64 << 20))
os.remove(path("nul.obj"))

# the same MTL named 20,000 times, and a 1 MB MTL named 200 times: each read once, warnings bounded
write("m.mtl", "newmtl red\nKd 1 0 0\n" + "# padding\n" * 100_000)
obj = "mtllib m.mtl\n" * 20_000 + "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n"
r = run("info", write("many_mtllib.obj", obj))
expect("the same MTL 20,000 times", r, codes=(0,))
check(r.err.count("\n") < 100, f"the same MTL 20,000 times: {r.err.count(chr(10))} lines of warnings")
check(r.seconds < time_limit / 3, f"the same MTL 20,000 times took {r.seconds:.1f} s")

# a submesh name of 4 MB copied into many submeshes
name = "o" * (4 << 20)
obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\no " + name + "\n" + "g a\nf 1 2 3\ng b\nf 1 2 3\n" * 1000
r = run("info", write("long_names.obj", obj))
expect("a 4 MB object name over 2,000 submeshes", r, codes=(0, 2), names="long_names.obj",
       max_bytes=BASE + (64 << 20) + 4 * len(obj) + 14 * len(obj))
check(len(r.err) < 10_000, f"a 4 MB name: {len(r.err)} bytes of messages (names must be cut when quoted)")
os.remove(path("long_names.obj"))

# a byte order mark before the first `v`: the vertex is kept, the faces stay where they were
r = run("info", write("bom.obj", "\ufeffv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"))
expect("a BOM", r, codes=(0,))
if r.code == 0:
    check(json.loads(r.out)["vertices"] == 3, f"a BOM: {r.out[:200]}")

# --- .sk, .skw and pose JSON: linear in their size ---
bones = 65_535
sk("big.sk", bones, (0, 0.001, 0))
write("big_pose.json", json.dumps({"bones": {f"bone{i}": {"rotation": [0.0, 0.0, 0.01]} for i in range(bones)}}))
write("one.obj", "v 0 0 0\nv 0 0.001 0\nv 0.001 0 0\nf 1 2 3\n")
skw("one.skw", ["0 1.0", "1 1.0", "1 1.0"])
r = run("skin", "one.obj", "--skeleton", "big.sk", "--weights", "one.skw", "--pose", "big_pose.json", "--out", "big.obj")
expect("a 65,535-bone pose", r, codes=(0, 2), names="big")
check(r.seconds < time_limit / 2, f"a 65,535-bone pose took {r.seconds:.1f} s")

skw("wide.skw", [" ".join(f"{i} 0.5" for i in range(bones)) + " 7 0.5", "1 1.0", "1 1.0"])
r = run("skin", "one.obj", "--skeleton", "big.sk", "--weights", "wide.skw", "--pose", "big_pose.json", "--out", "w.obj")
expect(".skw line of 65,535 pairs", r, codes=(2,), names="wide.skw")
check(r.seconds < time_limit / 2, f".skw line of 65,535 pairs took {r.seconds:.1f} s")

# --- numbers: finite translations near 3e38 overflow in the bind transforms ---
sk("huge.sk", 2, (0, 3e38, 0))
write("pose0.json", json.dumps({"bones": {}}))
skw("tri.skw", ["0 1.0", "1 1.0", "0 0.5 1 0.5"])
r = run("skin", "one.obj", "--skeleton", "huge.sk", "--weights", "tri.skw", "--pose", "pose0.json", "--out", "huge.obj")
expect("translations near 3e38", r, codes=(2,), names="huge.sk")
check(not os.path.exists(path("huge.obj")), "translations near 3e38: an output was written")

# JSON numbers that overflow, and a 10 MB key quoted in an error
write("overflow_pose.json", '{"bones": {"bone1": {"rotation": [1e999, 0, 0]}}}')
r = run("skin", "one.obj", "--skeleton", "two.sk", "--weights", "one.skw", "--pose", "overflow_pose.json",
        "--out", "o.obj")
expect("a JSON number that overflows", r, codes=(2,), names="overflow_pose.json")
write("long_key.json", '{"bones": {"' + "k" * (10 << 20) + '": {"rotation": [0, 0, 0]}}}')
r = run("skin", "one.obj", "--skeleton", "two.sk", "--weights", "one.skw", "--pose", "long_key.json", "--out", "o.obj")
expect("a 10 MB key", r, codes=(2,), names="long_key.json")
check(len(r.err) < 2000, f"a 10 MB key: the error is {len(r.err)} bytes")
os.remove(path("long_key.json"))

# a conditionally stable integrator past its bound: refused, never printed as numbers
r = run("simulate", "--builtin", "--target", "1.3,1.6,0.4", "--dt", "2", "--seconds", "4", "--integrator", "verlet")
expect("Verlet at dt = 2", r, codes=(2,))

# --- outputs: what the user named keeps its kind and mode; nothing else is written ---
write("pose_ok.json", json.dumps({"bones": {"bone1": {"rotation": [0, 0, 30]}}}))
skin_ok = ["skin", "one.obj", "--skeleton", "two.sk", "--weights", "one.skw", "--pose", "pose_ok.json"]
# A device output, on a private copy of /dev/null (made where the test runs as root), so that a regression cannot
# replace the system's.
try:
    os.mknod(path("null"), stat.S_IFCHR | 0o666, os.makedev(1, 3))
except PermissionError:
    pass
if os.path.exists(path("null")):
    r = run(*skin_ok, "--out", "null")
    expect("--out a device", r, codes=(0,))
    check(stat.S_ISCHR(os.stat(path("null")).st_mode), "--out a device: the device was replaced by a file")
write("private.obj", "old\n")
os.chmod(path("private.obj"), 0o600)
r = run(*skin_ok, "--out", "private.obj")
expect("an existing 0600 output", r, codes=(0,))
check(stat.S_IMODE(os.stat(path("private.obj")).st_mode) == 0o600, "an existing 0600 output changed its mode")
write("target.obj", "old\n")
os.symlink("target.obj", path("link.obj"))
r = run(*skin_ok, "--out", "link.obj")
expect("a symlinked output", r, codes=(0,))
check(os.path.islink(path("link.obj")), "a symlinked output was replaced by a file")
check(open(path("target.obj")).read() != "old\n", "a symlinked output was not written through")
os.mkfifo(path("fifo.obj"))
r = run("info", "fifo.obj")
expect("a FIFO as input", r, codes=(2,), names="fifo.obj")
r = run(*skin_ok, "--out", "out/of/reach/x.obj")
expect("an output folder that does not exist", r, codes=(1, 2))
no_strays("outputs")
bad_utf8 = os.fsencode(path("caf")) + b"\xe9.obj"
r = run(*skin_ok, "--out", os.fsdecode(bad_utf8))
expect("a non-UTF-8 output path", r, codes=(0,))
check(os.path.exists(bad_utf8), "a non-UTF-8 output path: nothing written")

# --- imports (isolated): crashes, hangs and blow-ups in Assimp become exit 2 naming the file ---
if importer:
    mesh_tail = ('"meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "accessors": [{"bufferView": 0,'
                 ' "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],'
                 ' "bufferViews": [{"buffer": 0, "byteLength": 36}], "buffers": [{"byteLength": 36, "uri":'
                 ' "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]}')
    depth = 20_000
    chain = ",".join('{"children": [%d]}' % (i + 1) for i in range(depth)) + ',{"mesh": 0}'
    write("deep.gltf", '{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [' + chain +
          "], " + mesh_tail)
    r = run("info", "deep.gltf")
    expect("a glTF node chain 20,000 deep", r, names="deep.gltf")
    write("nested.gltf", '{"asset": {"version": "2.0"}, "extras": ' + "[" * 1_000_000 + "]" * 1_000_000 + "}")
    r = run("info", "nested.gltf")
    expect("glTF JSON nested a million levels", r, codes=(2,), names="nested.gltf")
    frames = "".join("Frame f%d {\n" % i for i in range(50_000)) + "}\n" * 50_000
    write("deep.x", "xof 0303txt 0032\n" + frames)
    r = run("info", "deep.x")
    expect(".x frames 50,000 deep", r, codes=(2,), names="deep.x")
    with open(path("huge_chunk.glb"), "wb") as f:
        f.write(b"glTF" + (2).to_bytes(4, "little") + (0xFFFFFFF0).to_bytes(4, "little") +
                (0xFFFFFFE0).to_bytes(4, "little") + b"JSON" + b'{"asset": {"version": "2.0"}}' + b" " * 600)
    if not sanitized:  # a sanitized worker may take the 4 GB (its limit is on resident memory): a test of the
        r = run("info", "huge_chunk.glb")  # library (import_isolated_test) runs it with a lower limit instead
        expect("a .glb claiming a 4 GB JSON chunk", r, codes=(2,), names="huge_chunk.glb")

    # names that would inject OBJ lines, and textures the user did not name
    os.makedirs(path("model"))
    os.makedirs(path("secret"))
    write("secret/key.png", "not for export")
    doc = json.loads('{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0,'
                     ' "name": "body\\nv 9 9 9\\nf 1 2 3\\\\"}], ' + mesh_tail)
    doc["meshes"][0]["name"] = "mesh\nusemtl x"
    doc["meshes"][0]["primitives"][0]["material"] = 0
    doc["materials"] = [{"name": "m", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
    doc["textures"] = [{"source": 0}]
    doc["images"] = [{"uri": "missing.png"}]
    write("model/named.gltf", json.dumps(doc))
    # An image outside the model's folder is refused at import, unread (tests/cli/confinement_test.py tries every
    # command and every kind of reference): nothing is exported.
    for uri in ("../secret/key.png", "/etc/passwd"):
        doc["images"] = [{"uri": uri}]
        write("model/outside.gltf", json.dumps(doc))
        r = run("export", "model/outside.gltf", "--out", "exported_outside")
        expect(f"export with an image at {uri}", r, codes=(2,), names="outside.gltf")
        check(not os.path.exists(path("exported_outside")), f"export with an image at {uri} wrote files")
    for model in ("named",):
        r = run("export", f"model/{model}.gltf", "--out", f"exported_{model}")
        expect(f"export {model}", r, codes=(0,))
        copied = sorted(os.listdir(path(f"exported_{model}"))) if os.path.isdir(path(f"exported_{model}")) else []
        check(copied == [f"{model}.{e}" for e in ("mtl", "obj", "sk", "skw")], f"export {model} wrote {copied}")
        if copied:
            with open(path(f"exported_{model}/{model}.obj")) as f:
                lines = f.read().splitlines()
            check(sum(1 for line in lines if line.startswith("v ")) == 3, f"export {model}: injected v lines")
            check(sum(1 for line in lines if line.startswith("f ")) == 1, f"export {model}: injected f lines")
            check(not any(line.endswith("\\") for line in lines), f"export {model}: a line ends with a backslash")
    no_strays("export")

if failures:
    print("\n".join(failures))
    sys.exit(1)
print("hostile inputs: every recipe kept its promise")
