#!/usr/bin/env python3
"""No byte from outside the model's folder (docs/security.md): a folder holds a secret file beside a folder of hostile
models that name it in every way a model can (glTF buffer and image URIs, plain and percent-encoded; OBJ `mtllib`,
relative and absolute; MTL `map_Kd`; a symbolic link inside the folder; the model a rig file names). Every command
that reads a model must exit 2, naming the model, and no output file and no message may hold the secret's bytes,
its first bytes as vertices, or its size. With --allow-outside naming the secret's folder, the same files are read:
the check that would catch a leak does catch it.
Usage: confinement_test.py DEFORM WORK_DIR IMPORT(0|1) SAMPLES_DATA"""
import base64, json, os, secrets, shutil, struct, subprocess, sys

deform, work, importer, samples = os.path.abspath(sys.argv[1]), sys.argv[2], sys.argv[3] == "1", sys.argv[4]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
work = os.path.realpath(work)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def write(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb" if isinstance(data, bytes) else "w") as f:
        f.write(data)
    return path


# The secret: a marker and random bytes, 3 * 3 * 457 bytes (30 whole triangles of UNSIGNED_BYTE VEC3 positions).
secret_dir = os.path.join(work, "private")
marker = ("SECRET-" + secrets.token_hex(12)).encode()
secret = marker + secrets.token_bytes(3 * 3 * 457 - len(marker))
secret_path = write(os.path.join(secret_dir, "secret.bin"), secret)
size = str(len(secret))
# What the secret would look like once read as vertices: its first bytes as OBJ numbers and as glTF floats.
as_obj_vertex = f"v {secret[0]} {secret[1]} {secret[2]}".encode()
as_floats = struct.pack("<3f", secret[0], secret[1], secret[2])

models = os.path.join(work, "models", "m")  # two levels below work: "../../private/secret.bin" reaches the secret
relative = "../../private/secret.bin"
triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n"


def gltf_with_buffer(uri, byte_length):
    return json.dumps({
        "asset": {"version": "2.0"}, "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "buffers": [{"uri": uri, "byteLength": byte_length}],
        "bufferViews": [{"buffer": 0, "byteLength": byte_length}],
        "accessors": [{"bufferView": 0, "componentType": 5121, "count": byte_length // 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [255, 255, 255]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0})


def gltf_with_image(uri):
    positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<6f", 0, 0, 1, 0, 0, 1)
    data = "data:application/octet-stream;base64," + base64.b64encode(positions).decode()
    return json.dumps({
        "asset": {"version": "2.0"},
        "buffers": [{"uri": data, "byteLength": len(positions)}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],
        "images": [{"uri": uri}], "textures": [{"source": 0}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0})


gltf_models = {
    "buffer.gltf": gltf_with_buffer(relative, len(secret)),
    "buffer_encoded.gltf": gltf_with_buffer("..%2f..%2fprivate%2fsecret.bin", len(secret)),
    "buffer_absolute.gltf": gltf_with_buffer(secret_path, len(secret)),
    "buffer_wrong_length.gltf": gltf_with_buffer(relative, 12),  # must not learn the real size from the message
    "image.gltf": gltf_with_image(relative),
    "image_encoded.gltf": gltf_with_image("%2e%2e/%2e%2e/private/secret.bin"),
}
for name, text in gltf_models.items():
    write(os.path.join(models, name), text)
obj_models = {
    "mtllib_relative.obj": f"mtllib {relative}\n" + triangle,
    "mtllib_absolute.obj": f"mtllib {secret_path}\n" + triangle,
    "map_kd.obj": "mtllib map_kd.mtl\nusemtl a\n" + triangle,
    "symlink.obj": "mtllib link.mtl\n" + triangle,
}
for name, text in obj_models.items():
    write(os.path.join(models, name), text)
write(os.path.join(models, "map_kd.mtl"), f"newmtl a\nmap_Kd {relative}\n")
os.symlink(secret_path, os.path.join(models, "link.mtl"))
write(os.path.join(models, "rig.json"), json.dumps(
    {"model": {"obj": relative, "skeleton": "x.sk", "weights": "x.skw"}, "lattices": []}))
pose = write(os.path.join(work, "pose.json"), '{"bones": {}}')
lattice = write(os.path.join(work, "lattice.json"), '{"origin": [0, 0, 0], "size": [1, 1, 1]}')
sk = os.path.join(samples, "builtin.sk")
skw = write(os.path.join(work, "x.skw"), "not read\n")
outputs = os.path.join(work, "out")


last_stdout = b""


def run(args):
    global last_stdout
    p = subprocess.run([deform, *args], capture_output=True, cwd=work, timeout=300)
    last_stdout = p.stdout
    return p.returncode, p.stdout + p.stderr


def leaks(blob):
    """What of the secret `blob` holds: its marker, its bytes as OBJ vertices or glTF floats."""
    found = []
    if marker in blob:
        found.append("its bytes")
    if as_obj_vertex in blob:
        found.append("its bytes as OBJ vertices")
    if as_floats in blob:
        found.append("its bytes as glTF floats")
    return found


def output_leaks():
    found = []
    for folder, _, files in os.walk(outputs):
        for name in files:
            with open(os.path.join(folder, name), "rb") as f:
                found += [f"{name}: {what}" for what in leaks(f.read())]
    return found


def expect_refused(label, args, model):
    shutil.rmtree(outputs, ignore_errors=True)
    os.makedirs(outputs)
    code, messages = run(args)
    check(code == 2, f"{label}: exit {code}, expected 2: {messages[-300:]!r}")
    stem = os.path.splitext(os.path.basename(model))[0].encode()  # the model, or the MTL file it names (map_kd)
    check(stem in messages, f"{label}: the message does not name {model}: {messages!r}")
    for what in leaks(messages):
        failures.append(f"{label}: a message holds the secret ({what})")
    check(size.encode() not in messages or size in open(model).read(),
          f"{label}: a message gives the secret's size {size}: {messages!r}")
    for what in output_leaks():
        failures.append(f"{label}: an output holds the secret ({what})")


def model_commands(model, native):
    """Every command that reads `model`, as (label, args), outputs under `outputs`."""
    triple = ["--skeleton", sk, "--weights", skw] if native else []
    commands = [
        ("info", ["info", model]),
        ("export --format gltf",
         ["export", model, *triple, "--format", "gltf", "--out", os.path.join(outputs, "o.gltf")]),
        ("skin", ["skin", model, *triple, "--pose", pose, "--out", os.path.join(outputs, "s.obj")]),
        ("simplify", ["simplify", model, *triple, "--ratio", "0.5", "--out", os.path.join(outputs, "l.glb")]),
    ]
    if importer:  # the native export needs the importer component, even for native files
        commands.append(("export", ["export", model, *triple, "--out", os.path.join(outputs, "native")]))
    if native:
        commands += [
            ("weights", ["weights", model, "--skeleton", sk, "--out", os.path.join(outputs, "w.skw")]),
            ("ffd", ["ffd", model, "--lattice", lattice, "--out", os.path.join(outputs, "f.obj")]),
            ("bake (ffd)", ["bake", model, "--lattice", lattice, "--out", os.path.join(outputs, "b.glb")]),
        ]
    return commands


if importer:
    for name in gltf_models:
        model = os.path.join("models", "m", name)
        for label, args in model_commands(model, False):
            expect_refused(f"{name}: {label}", args, model)
for name in obj_models:
    model = os.path.join("models", "m", name)
    for label, args in model_commands(model, True):
        expect_refused(f"{name}: {label}", args, model)
rig = os.path.join("models", "m", "rig.json")
for label, args in [("simulate", ["simulate", rig, "--target", "1,1,1", "--seconds", "0.1"]),
                    ("bake", ["bake", rig, "--target", "1,1,1", "--seconds", "0.1",
                              "--out", os.path.join(outputs, "r.glb")])]:
    expect_refused(f"rig.json: {label}", args, rig)

# A name inside the folder that does not exist stays a warning, printed on one line whatever bytes it holds.
if importer:
    model = write(os.path.join(models, "newline.gltf"), gltf_with_image("missing%0Adeform%3A%20forged.png"))
    code, messages = run(["info", model])
    check(code == 0, f"info newline.gltf: exit {code}: {messages[-300:]!r}")
    check(b"\ndeform: forged" not in messages and b"\\x0a" in messages,
          f"info newline.gltf: a name from the file broke the warning's line: {messages[-300:]!r}")

# --allow-outside reads the same files on purpose: the checks above see a leak when there is one.
allow = ["--allow-outside", secret_dir]
if importer:
    model = os.path.join("models", "m", "buffer.gltf")
    code, messages = run(["info", model, *allow])
    check(code == 0, f"info --allow-outside: exit {code}: {messages[-300:]!r}")
    if code == 0:
        check(json.loads(last_stdout)["vertices"] > 0, "info --allow-outside: no vertices")
    shutil.rmtree(outputs, ignore_errors=True)
    code, messages = run(["export", model, "--out", os.path.join(outputs, "native"), *allow])
    check(code == 0, f"export --allow-outside: exit {code}: {messages[-300:]!r}")
    check(any("as OBJ vertices" in s for s in output_leaks()),
          "export --allow-outside: the secret's bytes were not found as vertices (the leak check cannot see them)")
    code, messages = run(["info", os.path.join("models", "m", "image.gltf"), *allow])
    check(code == 0, f"info image.gltf --allow-outside: exit {code}: {messages[-300:]!r}")
    # Only the folders named: another folder allows nothing more.
    code, messages = run(["info", model, "--allow-outside", os.path.join(work, "models")])
    check(code == 2, f"info --allow-outside (another folder): exit {code}")
code, messages = run(["info", os.path.join("models", "m", "mtllib_relative.obj"), *allow])
check(code == 0, f"info mtllib_relative.obj --allow-outside: exit {code}: {messages[-300:]!r}")
code, messages = run(["info", os.path.join("models", "m", "symlink.obj"), *allow])
check(code == 0, f"info symlink.obj --allow-outside: exit {code}: {messages[-300:]!r}")
# The MTL read on purpose: its unknown first line is quoted (the secret's marker), which shows the refusals above
# kept it out.
check(marker in messages, "info symlink.obj --allow-outside: the MTL's unknown statement was not quoted")

for f in failures:
    print("FAIL:", f)
print(f"{len(failures)} failures")
sys.exit(1 if failures else 0)
