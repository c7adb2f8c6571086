#!/usr/bin/env python3
"""glTF out end to end: `deform export --format gltf` (the built-in character as .gltf and .glb, an imported
character with clips from Debian's assimp-testmodels) and `deform bake` (the reach-stretch-release, an FFD). Every
file written passes the Khronos validator (npm gltf-validator, installed by `npm ci --prefix tests/node`) with no
errors (warnings and infos are reported), writes nothing but what was named, and reads back with the same positions
(within 1e-5 of the bounding-box diagonal):
  - exports, re-imported by deform's own importer: the bind-pose points, and the imported character posed by a clip;
  - bakes, decoded here (morph targets, sparse accessors): frame 0 of the FFD is the mesh, its last frame is what
    `deform ffd` writes, and the reach's rest shape is the character's bind pose.
Usage: gltf_test.py DEFORM NODE_DIR SAMPLES_DATA ASSIMP_MODELS WORK_DIR
Exit 77 (skipped) when node or the validator is not installed."""
import json, math, os, shutil, struct, subprocess, sys

deform, node_dir, samples, models, work = (os.path.abspath(a) for a in sys.argv[1:6])
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []
TOLERANCE = 1e-5  # of the bounding-box diagonal


def check(condition, message):
    if not condition:
        failures.append(message)
    return condition


def run(*args, expect=0):
    p = subprocess.run([deform, *args], capture_output=True, text=True, timeout=300, cwd=work)
    if not check(p.returncode == expect, f"deform {' '.join(args)}: exit {p.returncode}, stderr: {p.stderr}"):
        return None
    return json.loads(p.stdout) if expect == 0 and p.stdout.strip() else p


def obj_points(path):
    with open(path) as f:
        return [tuple(map(float, line.split()[1:4])) for line in f if line.startswith("v ")]


def diagonal(points):
    lo = [min(p[a] for p in points) for a in range(3)]
    hi = [max(p[a] for p in points) for a in range(3)]
    return math.dist(lo, hi)


class Grid:
    """Nearest point within `radius`, by hashing into cells of that size."""

    def __init__(self, points, radius):
        self.points, self.radius, self.cells = points, radius, {}
        for i, p in enumerate(points):
            self.cells.setdefault(self.key(p), []).append(i)

    def key(self, p):
        return tuple(math.floor(c / self.radius) for c in p)

    def nearest(self, p):
        k, best, best_d = self.key(p), None, self.radius
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for i in self.cells.get((k[0] + dx, k[1] + dy, k[2] + dz), ()):
                        d = math.dist(p, self.points[i])
                        if d <= best_d:
                            best, best_d = i, d
        return best


def correspondence(name, source, other):
    """other point -> source point at the same place (within the tolerance), or None with a failure."""
    radius = TOLERANCE * diagonal(source)
    grid = Grid(source, radius)
    # The same index when it is in place (points at one position with different weights stay apart), else the
    # nearest point.
    mapping = [i if i < len(source) and math.dist(p, source[i]) <= radius else grid.nearest(p)
               for i, p in enumerate(other)]
    missing = sum(1 for m in mapping if m is None)
    check(missing == 0, f"{name}: {missing} of {len(other)} points are not within {radius:g} of a source point")
    check(len(set(m for m in mapping if m is not None)) == len(source),
          f"{name}: the points read back do not cover the source's {len(source)} points")
    return mapping if missing == 0 else None


# --- a minimal glTF reader: enough to decode positions and morph targets ---
def load_gltf(path):
    data = open(path, "rb").read()
    if path.endswith(".glb"):
        magic, version, length = struct.unpack_from("<III", data, 0)
        check(magic == 0x46546C67 and version == 2 and length == len(data), f"{path}: bad GLB header")
        json_length, _ = struct.unpack_from("<II", data, 12)
        doc = json.loads(data[20:20 + json_length])
        bin_length, _ = struct.unpack_from("<II", data, 20 + json_length)
        blob = data[28 + json_length:28 + json_length + bin_length]
    else:
        doc = json.loads(data)
        blob = open(os.path.join(os.path.dirname(path), doc["buffers"][0]["uri"]), "rb").read()
    return doc, blob


def read_accessor(doc, blob, index):
    a = doc["accessors"][index]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[a["type"]]
    fmt = {5126: "f", 5125: "I", 5123: "H"}[a["componentType"]]
    size = struct.calcsize(fmt)

    def view_values(view_index, offset, count, components, form):
        v = doc["bufferViews"][view_index]
        start = v.get("byteOffset", 0) + offset
        return list(struct.unpack_from(f"<{count * components}{form}", blob, start))

    n = a["count"]
    flat = view_values(a["bufferView"], a.get("byteOffset", 0), n, width, fmt) if "bufferView" in a else [0] * (n * width)
    if "sparse" in a:
        s = a["sparse"]
        idx_fmt = {5125: "I", 5123: "H", 5121: "B"}[s["indices"]["componentType"]]
        indices = view_values(s["indices"]["bufferView"], s["indices"].get("byteOffset", 0), s["count"], 1, idx_fmt)
        values = view_values(s["values"]["bufferView"], s["values"].get("byteOffset", 0), s["count"], width, fmt)
        for j, i in enumerate(indices):
            flat[i * width:(i + 1) * width] = values[j * width:(j + 1) * width]
    del size
    return [tuple(flat[i * width:(i + 1) * width]) for i in range(n)]


def baked_frames(path):
    """(rest positions, [frame positions]) over every primitive's vertices, concatenated."""
    doc, blob = load_gltf(path)
    rest, frames = [], None
    for primitive in doc["meshes"][0]["primitives"]:
        base = read_accessor(doc, blob, primitive["attributes"]["POSITION"])
        rest += base
        targets = [read_accessor(doc, blob, t["POSITION"]) for t in primitive["targets"]]
        if frames is None:
            frames = [[] for _ in targets]
        for k, t in enumerate(targets):
            frames[k] += [tuple(b[a] + d[a] for a in range(3)) for b, d in zip(base, t)]
    return doc, rest, frames


# --- the validator ---
validator = os.path.join(node_dir, "validate_gltf.js")
if shutil.which("node") is None or not os.path.isdir(os.path.join(node_dir, "node_modules", "gltf-validator")):
    print("skipped: node or tests/node/node_modules/gltf-validator is missing (npm ci --prefix tests/node)")
    sys.exit(77)


def validate(files):
    p = subprocess.run(["node", validator, *files], capture_output=True, text=True, timeout=300,
                       env={**os.environ, "NODE_PATH": os.path.join(node_dir, "node_modules")})
    check(p.returncode == 0, f"validator failed: {p.stderr}")
    for line in p.stdout.splitlines():
        r = json.loads(line)
        name = os.path.relpath(r["file"], work)
        print(f"{name}: {os.path.getsize(r['file'])} bytes; validator: {r['errors']} errors, {r['warnings']} warnings, "
              f"{r['infos']} infos, {r['hints']} hints")
        for m in r["messages"][:5]:
            print("   ", m)
        check(r["errors"] == 0, f"{name}: the validator reports {r['errors']} errors: {r['messages'][:10]}")


written = []


def expect_only(folder, names):
    present = sorted(os.listdir(folder))
    check(present == sorted(names), f"{folder}: expected exactly {sorted(names)}, found {present}")


# --- export: the built-in character, .gltf (+ .bin) and .glb ---
os.makedirs(os.path.join(work, "gltf"))
out = run("export", "--builtin", "--format", "gltf", "--out", "gltf/builtin.gltf")
if out:
    # Its clips and its texture (painted by code: no file to find, no warning) come with it.
    check(out["bin"] == "gltf/builtin.bin" and out["bones"] == 33 and
          out["clips"] == ["idle", "walk", "run", "wave"] and out["textures"] == 1, f"export builtin: {out}")
expect_only(os.path.join(work, "gltf"), ["builtin.gltf", "builtin.bin"])
p = subprocess.run([deform, "export", "--builtin", "--format", "gltf", "--out", "builtin.glb"], capture_output=True,
                   text=True, timeout=300, cwd=work)
check(p.returncode == 0 and "builtin.png" not in p.stderr, f"export --builtin .glb: {p.returncode} {p.stderr}")
written += ["gltf/builtin.gltf", "builtin.glb"]
with open(os.path.join(work, "gltf", "builtin.gltf")) as f:
    builtin_doc = json.load(f)
check([a["name"] for a in builtin_doc.get("animations", [])] == ["idle", "walk", "run", "wave"],
      f"builtin.gltf animations: {[a.get('name') for a in builtin_doc.get('animations', [])]}")
check(len(builtin_doc.get("images", [])) == 1 and builtin_doc["images"][0].get("mimeType") == "image/png",
      f"builtin.gltf images: {builtin_doc.get('images')}")
# The native triple of samples/data, whose material has a PNG texture in the model's folder: it is embedded.
out = run("export", os.path.join(samples, "builtin.obj"), "--skeleton", os.path.join(samples, "builtin.sk"),
          "--weights", os.path.join(samples, "builtin.skw"), "--format", "gltf", "--out", "textured.glb")
if out:
    check(out["textures"] == 1, f"export textured: {out['textures']} textures embedded, not 1")
written.append("textured.glb")
run("export", "--builtin", "--out", "native")
source = obj_points(os.path.join(work, "native", "builtin.obj"))
for name in ("gltf/builtin.gltf", "builtin.glb"):
    back = run("export", name, "--out", "back-" + name.replace("/", "-"))
    if back:
        check(back["bones"] == 33, f"{name} re-imported: {back['bones']} bones, not 33")
        correspondence(name + " (bind pose)", source, obj_points(os.path.join(work, back["obj"])))

# A .gltf whose name a URI cannot hold as it is: the .bin's name is made safe, and the importer finds it.
out = run("export", "--builtin", "--format", "gltf", "--out", "my model%.gltf")
if out:
    check(out["bin"] == "my_model_.bin", f"export 'my model%.gltf': bin {out['bin']}")
    back = run("export", "my model%.gltf", "--out", "back-spaces")
    if back:
        correspondence("my model%.gltf (bind pose)", source, obj_points(os.path.join(work, back["obj"])))
written.append("my model%.gltf")

def check_posed(source, exported, mapping, clip, time, turn=lambda points: points):
    """`deform skin` of the exported file gives the source's posed points (turned by `turn`) at `mapping`."""
    a = run("skin", source, "--clip", clip, "--time", time, "--out", "posed-source.obj")
    b = run("skin", exported, "--clip", clip, "--time", time, "--out", "posed-back.obj")
    if a and b and mapping:
        posed_source = turn(obj_points(os.path.join(work, "posed-source.obj")))
        posed_back = obj_points(os.path.join(work, "posed-back.obj"))
        limit = TOLERANCE * diagonal(posed_source)
        worst = max(math.dist(posed_back[i], posed_source[j]) for i, j in enumerate(mapping))
        check(worst <= limit, f"{exported} posed by {clip} at {time} s: a point is {worst:g} from the source's "
              f"(limit {limit:g})")


# --- export: an imported character with clips, posed by a clip after the round trip ---
wuson = os.path.join(models, "X", "Testwuson.X")
if os.path.exists(wuson):
    out = run("export", wuson, "--format", "gltf", "--out", "wuson.glb")
    written.append("wuson.glb")
    native, back = run("export", wuson, "--out", "wuson-native"), run("export", "wuson.glb", "--out", "wuson-back")
    if out and native and back:
        check(back["clips"] == native["clips"] == out["clips"], f"clips: {native['clips']} -> {back['clips']}")
        check(back["bones"] == native["bones"], f"bones: {native['bones']} -> {back['bones']}")
        mapping = correspondence("wuson.glb (bind pose)", obj_points(os.path.join(work, native["obj"])),
                                 obj_points(os.path.join(work, back["obj"])))
        for clip, time in (("Wuson_Run", "0.37"), ("Wuson_Walk", "1.1")):
            check_posed(wuson, "wuson.glb", mapping, clip, time)
else:
    print(f"skipped the imported character: {wuson} is missing (Debian's assimp-testmodels)")

# --- export: a Z-up import (IQM is +Z up) is written turned into glTF's +Y up, (x, y, z) -> (x, z, -y), so that
# viewers stand it upright; re-imported it comes back turned, in the bind pose and posed by a clip ---
mrfixit = os.path.join(models, "IQM", "mrfixit.iqm")
if os.path.exists(mrfixit):
    out = run("export", mrfixit, "--format", "gltf", "--out", "mrfixit.glb")
    written.append("mrfixit.glb")
    native = run("export", mrfixit, "--out", "mrfixit-native")
    back = run("export", "mrfixit.glb", "--out", "mrfixit-back")
    if out and native and back:
        def turned(points):
            return [(x, z, -y) for x, y, z in points]
        mapping = correspondence("mrfixit.glb (bind pose, turned)",
                                 turned(obj_points(os.path.join(work, native["obj"]))),
                                 obj_points(os.path.join(work, back["obj"])))
        check_posed(mrfixit, "mrfixit.glb", mapping, "idle", "0.7", turned)
else:
    print(f"skipped the Z-up character: {mrfixit} is missing (Debian's assimp-testmodels)")

# --- bake: the FFD of a box around the head, and the reach-stretch-release ---
lattice = {"origin": [-0.3, 1.4, -0.2], "size": [0.6, 0.5, 0.5], "degree": [2, 2, 2],
           "displacements": [{"index": [1, 2, 1], "offset": [0.0, 0.25, 0.05]},
                             {"index": [2, 1, 1], "offset": [0.1, 0.0, 0.0]}]}
with open(os.path.join(work, "head.json"), "w") as f:
    json.dump(lattice, f)
mesh = os.path.join(samples, "builtin.obj")
out = run("bake", mesh, "--lattice", "head.json", "--seconds", "1", "--fps", "10", "--out", "ffd.gltf")
written.append("ffd.gltf")
run("ffd", mesh, "--lattice", "head.json", "--out", "ffd-last.obj")
if out:
    check(out["frames"] == 11, f"bake ffd: {out['frames']} frames, not 11")
    doc, rest, frames = baked_frames(os.path.join(work, "ffd.gltf"))
    times = read_accessor(doc, load_gltf(os.path.join(work, "ffd.gltf"))[1],
                          doc["animations"][0]["samplers"][0]["input"])
    check([round(t[0], 6) for t in times] == [round(k / 10, 6) for k in range(11)], f"bake ffd times: {times}")
    points = obj_points(mesh)
    mapping = correspondence("ffd.gltf (rest)", points, rest)
    deformed = obj_points(os.path.join(work, "ffd-last.obj"))
    limit = TOLERANCE * diagonal(points)
    if mapping:
        worst0 = max(math.dist(frames[0][i], points[j]) for i, j in enumerate(mapping))
        worst = max(math.dist(frames[-1][i], deformed[j]) for i, j in enumerate(mapping))
        check(worst0 <= limit, f"ffd.gltf frame 0 is {worst0:g} from the mesh (limit {limit:g})")
        check(worst <= limit, f"ffd.gltf last frame is {worst:g} from `deform ffd`'s output (limit {limit:g})")
        moved = max(math.dist(frames[-1][i], points[j]) for i, j in enumerate(mapping))
        check(moved > 0.02, f"ffd.gltf: the last frame moves no point by more than {moved:g}")

out = run("bake", "--builtin", "--target", "1.3,1.6,0.4", "--release-at", "1", "--seconds", "2", "--fps", "15",
          "--out", "reach.glb")
written.append("reach.glb")
if out:
    check(out["frames"] == 31, f"bake reach: {out['frames']} frames, not 31")
    dense = out["frames"] * out["render_vertices"] * 2
    print(f"reach.glb: {out['stored_displacements']} of {dense} displacements stored (sparse), {out['bytes']} bytes")
    check(out["stored_displacements"] < dense / 2, "bake reach: the sparse targets store more than half the vertices")
    doc, rest, frames = baked_frames(os.path.join(work, "reach.glb"))
    mapping = correspondence("reach.glb (rest = bind pose)", source, rest)
    if mapping:
        limit = TOLERANCE * diagonal(source)
        moved = [max(math.dist(f[i], source[j]) for i, j in enumerate(mapping)) for f in frames]
        check(moved[0] > 0.1, f"reach.glb: frame 0 (after the reach) moves no point by more than {moved[0]:g}")
        check(all(math.isfinite(m) for m in moved), "reach.glb: a frame is not finite")
        # The stretch springs back after the release: the last frames settle (consecutive frames nearly equal).
        last = max(math.dist(a, b) for a, b in zip(frames[-1], frames[-2]))
        first = max(math.dist(a, b) for a, b in zip(frames[1], frames[0]))
        check(last < first or first == 0, f"reach.glb: the motion does not settle ({first:g} -> {last:g})")

# --- bake --clip: the built-in walk with its jiggle (every lattice of the rig given inertia), and an import's clip ---
rig = {"rig": 1, "model": "builtin", "reach": {"effector": "hand_l", "root": "clavicle_l"},
       "lattices": [{"name": n, "bone": n, "motion": {"inertia": 1}} for n in ("upperarm_l", "forearm_l", "hand_l")]}
with open(os.path.join(work, "jiggle.rig.json"), "w") as f:
    json.dump(rig, f)
walks = {}
for name, args in (("walk.glb", ["--builtin"]), ("walk-jiggle.glb", ["--builtin", "--rig", "jiggle.rig.json"]),
                   ("walk-inertia1.glb", ["--builtin", "--inertia", "1"]),
                   ("walk-inertia0.glb", ["--builtin", "--inertia", "0"])):
    out = run("bake", *args, "--clip", "walk", "--fps", "10", "--out", name)
    written.append(name)
    if out:
        check(out["frames"] == 11, f"bake {name}: {out['frames']} frames, not 11 (the walk's 1 s at 10 fps)")
        doc, rest, frames = baked_frames(os.path.join(work, name))
        check(doc["animations"][0]["name"] == "walk", f"bake {name}: animation {doc['animations'][0]['name']}")
        check(len(doc.get("images", [])) == 1, f"bake {name}: the texture is not embedded")
        walks[name] = frames
if len(walks) == 4:
    # The walk moves the body; the jiggle moves the left arm's points away from the rigid walk's.
    a, b = walks["walk.glb"], walks["walk-jiggle.glb"]
    check(max(math.dist(p, q) for p, q in zip(a[5], a[0])) > 0.05, "bake --clip walk: the body does not move")
    jiggle = max(math.dist(p, q) for k in range(len(a)) for p, q in zip(a[k], b[k]))
    check(jiggle > 1e-3, f"bake --clip walk --rig jiggle: the lattices' inertia moves no point ({jiggle:g})")
    # --inertia 1: every lattice at its part's tuned inertia, so the flesh jiggles; 0: the built-in rig's own (none).
    tuned = max(math.dist(p, q) for k in range(len(a)) for p, q in zip(a[k], walks["walk-inertia1.glb"][k]))
    check(tuned > 1e-3, f"bake --clip walk --inertia 1: no point jiggles ({tuned:g})")
    still = max(math.dist(p, q) for k in range(len(a)) for p, q in zip(a[k], walks["walk-inertia0.glb"][k]))
    check(still == 0.0, f"bake --clip walk --inertia 0 differs from the built-in rig's walk by {still:g}")
if os.path.exists(wuson):
    out = run("bake", wuson, "--clip", "Wuson_Walk", "--seconds", "0.5", "--fps", "8", "--out", "wuson-walk.glb")
    written.append("wuson-walk.glb")
    if out:
        check(out["frames"] == 5, f"bake wuson --clip: {out['frames']} frames, not 5")
        doc, rest, frames = baked_frames(os.path.join(work, "wuson-walk.glb"))
        check(doc["animations"][0]["name"] == "Wuson_Walk", "bake wuson --clip: the animation is not the clip's")
        check(max(math.dist(p, q) for p, q in zip(frames[2], frames[0])) > 0, "bake wuson --clip: nothing moves")
    run("bake", wuson, "--clip", "Dance", "--out", "none.glb", expect=2)

# --- bad usage writes nothing ---
run("export", "--builtin", "--format", "gltf", "--out", "x.obj", expect=2)
run("export", "--builtin", "--format", "fbx", "--out", "x.glb", expect=2)
run("bake", "--builtin", "--target", "1.3,1.6,0.4", "--fps", "0", "--out", "bad.glb", expect=2)
run("bake", mesh, "--lattice", "head.json", "--target", "1,1,1", "--out", "bad.glb", expect=2)
run("bake", mesh, "--lattice", "head.json", "--inertia", "1", "--out", "bad.glb", expect=2)
run("bake", "--builtin", "--clip", "walk", "--inertia", "1.5", "--out", "bad.glb", expect=2)
for name in ("x.obj", "x.glb", "bad.glb", "none.glb"):
    check(not os.path.exists(os.path.join(work, name)), f"{name} was written by a failed command")

validate([os.path.join(work, name) for name in written])
leftovers = [n for root, _, files in os.walk(work) for n in files if "deform-tmp" in n]
check(not leftovers, f"temporary files left: {leftovers}")

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
