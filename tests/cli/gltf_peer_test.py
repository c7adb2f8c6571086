#!/usr/bin/env python3
"""glTF skinning checked against a peer: three.js (tests/node/three_skin.mjs: GLTFLoader, AnimationMixer,
SkinnedMesh.getVertexPosition) and `deform skin MODEL --clip C --time T` must put every triangle corner within 1e-5 of
the bounding-box diagonal of each other, on the glTF models of Debian's assimp-testmodels and on files written here
(STEP and CUBICSPLINE clips, two same-named rigs apart, non-uniform node scale, several meshes on one skin,
quantised and sparse accessors, eight influences per vertex, morph targets under a skin with LINEAR, STEP and
CUBICSPLINE weight channels, sparse targets, and `--morph` overrides against three's morphTargetInfluences). Every
file is held to the tolerance: there are no known gaps. three.js skins with four influences; three_skin.mjs sums
the further JOINTS_n / WEIGHTS_n sets with three's own bone matrices (see there).
Usage: gltf_peer_test.py DEFORM NODE_DIR WORK_DIR [MODELS_DIR]
Exits 77 (skipped) when node or three.js is missing (scripts/test installs it: npm ci --prefix tests/node)."""
import base64, glob, json, math, os, shutil, struct, subprocess, sys

deform, node_dir, work = sys.argv[1], sys.argv[2], sys.argv[3]
models = sys.argv[4] if len(sys.argv) > 4 else "/usr/share/assimp/models"
if shutil.which("node") is None or not os.path.isdir(os.path.join(node_dir, "node_modules", "three")):
    print("skipped: node or three.js missing (npm ci --prefix tests/node)")
    sys.exit(77)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []
TOLERANCE = 1e-5


def three(model, animation=None, time=None, morphs=None):
    args = ["node", os.path.join(node_dir, "three_skin.mjs"), model]
    if animation is not None:
        args += [str(animation), repr(time)]
    env = dict(os.environ)
    if morphs:
        env["MORPHS"] = json.dumps(morphs)
    p = subprocess.run(args, capture_output=True, text=True, timeout=120, env=env)
    if p.returncode != 0:
        return None, p.stderr.strip().splitlines()[-1:] or ["exit %d" % p.returncode]
    return json.loads(p.stdout), None


def deform_skin(model, clip=None, time=None, morphs=None):
    out = os.path.join(work, "skinned.obj")
    args = [deform, "skin", model, "--out", out]
    if morphs:
        args += ["--morph", ",".join("%s:%r" % (k, v) for k, v in morphs.items())]
    if clip is None:
        pose = os.path.join(work, "bind.json")
        with open(pose, "w") as f:
            f.write('{"bones": {}}')
        args += ["--pose", pose]
    else:
        args += ["--clip", clip, "--time", repr(time)]
    p = subprocess.run(args, capture_output=True, text=True, timeout=120)
    if p.returncode != 0:
        return None, p.stderr.strip()
    v, corners = [], []
    with open(out) as f:
        for line in f:
            t = line.split()
            if t and t[0] == "v":
                v.append(tuple(map(float, t[1:4])))
            elif t and t[0] == "f":
                corners += [v[int(c.split("/")[0]) - 1] for c in t[1:]]
    return corners, p.stderr


def distance(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def diagonal(points):
    lo = [min(p[i] for p in points) for i in range(3)]
    hi = [max(p[i] for p in points) for i in range(3)]
    return max(distance(lo, hi), 1e-12)


def clip_names(model):
    """The names libdeform gives the file's animations: the file's, or clipN when empty or repeated."""
    if model.endswith(".glb"):
        with open(model, "rb") as f:
            data = f.read()
        doc = json.loads(data[20:20 + struct.unpack_from("<I", data, 12)[0]])
    else:
        with open(model) as f:
            doc = json.load(f)
    names = []
    for i, a in enumerate(doc.get("animations", [])):
        name = a.get("name", "")
        names.append(name if name and name not in names else "clip%d" % i)
    return names


results = []


def compare(label, model, times=(0.3, 0.77), may_refuse=False, morphs=None):
    names = clip_names(model)
    # Unposed, libdeform shows the skins' bind (its Model's bind pose) and three.js the node tree's rest: they agree
    # only in files without animations (a clip of libdeform holds every bone whose rest differs from its bind).
    cases = [(i, n, t) for i, n in enumerate(names) for t in times] or [(None, None, None)]
    worst = 0.0
    for index, name, time in cases:
        peer, error = three(model, index, time, morphs)
        if peer is None:
            results.append("%s: three.js cannot load it (%s)" % (label, error[0] if error else "?"))
            return
        ours, message = deform_skin(model, name, time, morphs)
        what = "%s %s" % (label, "bind" if name is None else "clip '%s' t=%g" % (name, time))
        if ours is None:
            results.append("%s: deform refuses it: %s" % (what, message))
            if not may_refuse:
                failures.append("%s: deform refuses a file three.js loads: %s" % (what, message))
            return
        theirs = peer["corners"]
        if len(ours) != len(theirs):
            failures.append("%s: %d triangle corners, three.js has %d" % (what, len(ours), len(theirs)))
            return
        size = diagonal(theirs)
        worst = max(worst, max((distance(a, b) for a, b in zip(ours, theirs)), default=0.0) / size)
    verdict = "ok" if worst <= TOLERANCE else "FAILED"
    results.append("%s: largest distance %.3g of the bbox diagonal over %d poses (%s)" %
                   (label, worst, len(cases), verdict))
    if worst > TOLERANCE:
        failures.append("%s: three.js and deform differ by %.3g of the bbox diagonal" % (label, worst))


# --- files written here ---
class Gltf:
    """A glTF 2.0 document with one embedded buffer."""

    def __init__(self):
        self.doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}], "nodes": [], "meshes": [],
                    "accessors": [], "bufferViews": [], "buffers": [], "skins": [], "animations": []}
        self.data = bytearray()

    def view(self, raw):
        while len(self.data) % 4:
            self.data.append(0)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.data), "byteLength": len(raw)})
        self.data += raw
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, values, kind, component=5126, normalized=False, minmax=False):
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[kind]
        fmt = {5126: "f", 5120: "b", 5121: "B", 5122: "h", 5123: "H", 5125: "I"}[component]
        flat = [x for v in values for x in (v if isinstance(v, (list, tuple)) else [v])]
        raw = struct.pack("<%d%s" % (len(flat), fmt), *flat)
        if component in (5120, 5121, 5122, 5123) and kind != "SCALAR":  # elements aligned to 4 bytes
            size = struct.calcsize(fmt) * width
            padded = (size + 3) // 4 * 4
            if padded != size:
                raw = b"".join(raw[i * size:(i + 1) * size] + b"\0" * (padded - size) for i in range(len(values)))
        a = {"bufferView": self.view(raw), "componentType": component, "count": len(values), "type": kind}
        if component in (5120, 5121, 5122, 5123) and kind != "SCALAR" and (struct.calcsize(fmt) * width) % 4:
            self.doc["bufferViews"][-1]["byteStride"] = (struct.calcsize(fmt) * width + 3) // 4 * 4
        if normalized:
            a["normalized"] = True
        if minmax:
            a["min"] = [min(v[i] for v in values) for i in range(width)]
            a["max"] = [max(v[i] for v in values) for i in range(width)]
        self.doc["accessors"].append(a)
        return len(self.doc["accessors"]) - 1

    def node(self, **fields):
        self.doc["nodes"].append(fields)
        return len(self.doc["nodes"]) - 1

    def save(self, name):
        doc = dict(self.doc)
        doc["buffers"] = [{"byteLength": len(self.data),
                           "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.data)).decode()}]
        for key in ("skins", "animations"):
            if not doc[key]:
                del doc[key]
        path = os.path.join(work, name)
        with open(path, "w") as f:
            json.dump(doc, f)
        return path


def bar(g, x0=0.0, rows=5, height=2.0, joints=(0, 1), influences=None):
    """A vertical strip of quads at x0 (width 1, `rows` rows over `height`), weighted from joints[0] at the bottom to
    joints[1] at the top. Returns the primitive's attributes and indices accessors."""
    positions, joint_sets, weight_sets = [], [], []
    for r in range(rows):
        y = height * r / (rows - 1)
        for x in (x0 - 0.5, x0 + 0.5):
            positions.append([x, y, 0.1 * r * (x - x0)])
            w = r / (rows - 1)
            if influences is None:
                joint_sets.append([joints[0], joints[1], 0, 0])
                weight_sets.append([1 - w, w, 0.0, 0.0])
            else:
                joint_sets.append(influences[0](r, x))
                weight_sets.append(influences[1](r, x))
    indices = []
    for r in range(rows - 1):
        a, b, c, d = 2 * r, 2 * r + 1, 2 * r + 2, 2 * r + 3
        indices += [a, b, d, a, d, c]
    attributes = {"POSITION": g.accessor(positions, "VEC3", minmax=True)}
    if isinstance(joint_sets[0][0], list):  # several JOINTS_n / WEIGHTS_n sets
        for s in range(len(joint_sets[0])):
            attributes["JOINTS_%d" % s] = g.accessor([j[s] for j in joint_sets], "VEC4", 5123)
            attributes["WEIGHTS_%d" % s] = g.accessor([w[s] for w in weight_sets], "VEC4")
    else:
        attributes["JOINTS_0"] = g.accessor(joint_sets, "VEC4", 5123)
        attributes["WEIGHTS_0"] = g.accessor(weight_sets, "VEC4")
    return {"attributes": attributes, "indices": g.accessor(indices, "SCALAR", 5123)}


def translation_matrix(t):
    return [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, t[0], t[1], t[2], 1]


def quat_z(degrees):
    h = math.radians(degrees) / 2
    return [0.0, 0.0, math.sin(h), math.cos(h)]


def two_joint_rig(g, name_prefix="", x=0.0, root_extra=None):
    """Joints `Hips` at (x, 0, 0) and `Spine` 1 above it; returns (hips, spine, skin index)."""
    spine = g.node(name="Spine", translation=[0, 1, 0])
    hips_fields = {"name": "Hips", "translation": [x, 0, 0], "children": [spine]}
    hips_fields.update(root_extra or {})
    hips = g.node(**hips_fields)
    hips_world = [x, 0, 0]
    scale = (root_extra or {}).get("scale", [1, 1, 1])
    ibms = [translation_matrix([-hips_world[0], 0, 0]), translation_matrix([-hips_world[0], -1 * scale[1], 0])]
    g.doc["skins"].append({"joints": [hips, spine], "inverseBindMatrices": g.accessor(ibms, "MAT4")})
    return hips, spine, len(g.doc["skins"]) - 1


def animate(g, targets, interpolation="LINEAR", name="move"):
    """One animation: each (node, path, times, values) a channel with its own sampler."""
    animation = {"name": name, "channels": [], "samplers": []}
    for node, path, times, values in targets:
        kind = "VEC4" if path == "rotation" else "VEC3"
        animation["samplers"].append({"input": g.accessor(times, "SCALAR", minmax=False), "interpolation": interpolation,
                                      "output": g.accessor(values, kind)})
        g.doc["accessors"][animation["samplers"][-1]["input"]].update({"min": [min(times)], "max": [max(times)]})
        animation["channels"].append({"sampler": len(animation["samplers"]) - 1, "target": {"node": node, "path": path}})
    g.doc["animations"].append(animation)


def simple(name, interpolation="LINEAR", root_extra=None, rotations=None, translations=None):
    g = Gltf()
    hips, spine, skin = two_joint_rig(g, root_extra=root_extra)
    g.doc["meshes"].append({"name": "bar", "primitives": [bar(g)]})
    body = g.node(name="body", mesh=0, skin=skin)
    g.doc["scenes"][0]["nodes"] = [hips, body]
    times = [0.0, 0.5, 1.0]
    targets = [(spine, "rotation", times, rotations or [quat_z(0), quat_z(40), quat_z(-30)])]
    if translations:
        targets.append((hips, "translation", times, translations))
    animate(g, targets, interpolation)
    return g, name


generated = []
# STEP: at 0.3 s the spine must still be at its first key (linear would be 24° on).
g, n = simple("step.gltf", "STEP", translations=[[0, 0, 0], [0.5, 0, 0], [0, 0.2, 0]])
generated.append((g.save(n), None))
# CUBICSPLINE: per key in-tangent, value, out-tangent.
g = Gltf()
hips, spine, skin = two_joint_rig(g)
g.doc["meshes"].append({"name": "bar", "primitives": [bar(g)]})
body = g.node(name="body", mesh=0, skin=skin)
g.doc["scenes"][0]["nodes"] = [hips, body]
rot = []
for deg, tangent in ((0, [0, 0, 0.3, 0]), (40, [0, 0, -0.2, 0.1]), (-30, [0, 0, 0.4, 0])):
    rot += [tangent, quat_z(deg), [-t for t in tangent]]
trans = []
for value, tangent in (([0, 0, 0], [1, 0, 0]), ([0.5, 0.2, 0], [0, 1, 0]), ([0, 0, 0.3], [-1, 0, 0])):
    trans += [tangent, value, tangent]
animate(g, [(spine, "rotation", [0.0, 0.5, 1.0], rot), (hips, "translation", [0.0, 0.5, 1.0], trans)], "CUBICSPLINE")
generated.append((g.save("cubic.gltf"), None))
# Two rigs with the same joint names standing 5 apart, each skinning its own bar.
g = Gltf()
rig_a = two_joint_rig(g, x=0.0)
rig_b = two_joint_rig(g, x=5.0)
g.doc["meshes"].append({"name": "bar_a", "primitives": [bar(g, 0.0)]})
g.doc["meshes"].append({"name": "bar_b", "primitives": [bar(g, 5.0)]})
a = g.node(name="body", mesh=0, skin=rig_a[2])
b = g.node(name="body", mesh=1, skin=rig_b[2])
g.doc["scenes"][0]["nodes"] = [rig_a[0], rig_b[0], a, b]
animate(g, [(rig_a[1], "rotation", [0.0, 1.0], [quat_z(0), quat_z(60)]),
            (rig_b[1], "rotation", [0.0, 1.0], [quat_z(0), quat_z(-45)]),
            (rig_b[0], "translation", [0.0, 1.0], [[5, 0, 0], [5, 0.5, 0]])])
generated.append((g.save("two_rigs.gltf"), None))
# Non-uniform scale on the Spine joint (constant: skinning stays exact) and a uniform scale 2 on the Hips.
g, n = simple("scaled.gltf", root_extra={"scale": [2, 2, 2]})
g.doc["nodes"][0]["scale"] = [1.0, 1.5, 0.7]
# The Spine's bind includes its own scale: IBM = inverse(T(0, 2, 0) · S(2 · (1, 1.5, 0.7))).
g.doc["accessors"][g.doc["skins"][0]["inverseBindMatrices"]]
ibm = [1 / 2, 0, 0, 0, 0, 1 / 3, 0, 0, 0, 0, 1 / 1.4, 0, 0, -2 / 3, 0, 1]
ibm_hips = [0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 1]
g.doc["skins"][0]["inverseBindMatrices"] = g.accessor([ibm_hips, ibm], "MAT4")
generated.append((g.save(n), None))
# Several meshes (and a mesh of two primitives) sharing one skin.
g = Gltf()
hips, spine, skin = two_joint_rig(g)
g.doc["meshes"].append({"name": "left", "primitives": [bar(g, -1.0), bar(g, -2.5)]})
g.doc["meshes"].append({"name": "right", "primitives": [bar(g, 1.0)]})
left = g.node(name="left", mesh=0, skin=skin)
right = g.node(name="right", mesh=1, skin=skin)
g.doc["scenes"][0]["nodes"] = [hips, left, right]
animate(g, [(spine, "rotation", [0.0, 1.0], [quat_z(0), quat_z(50)]), (hips, "rotation", [0.0, 1.0], [quat_z(0), quat_z(-20)])])
generated.append((g.save("shared_skin.gltf"), None))
# KHR_mesh_quantization: normalised short positions on a scaled node, unsigned byte weights; a sparse rotation output.
g = Gltf()
hips, spine, skin = two_joint_rig(g)
prim = bar(g)
positions = g.doc["accessors"][prim["attributes"]["POSITION"]]
pos_values = []
for r in range(5):
    for x in (-0.5, 0.5):
        pos_values.append([round(x * 0.5 * 32767), round(r / 4 * 32767), round(0.1 * r * x * 0.5 * 32767)])
prim["attributes"]["POSITION"] = g.accessor(pos_values, "VEC3", 5122, normalized=True, minmax=True)
weights = []
for r in range(5):
    for _ in range(2):
        w = round(255 * r / 4)
        weights.append([255 - w, w, 0, 0])
prim["attributes"]["WEIGHTS_0"] = g.accessor(weights, "VEC4", 5121, normalized=True)
g.doc["meshes"].append({"name": "quantised", "primitives": [prim]})
body = g.node(name="body", mesh=0, skin=skin)
# The quantised positions span [-0.25, 0.25] × [0, 1]: the skin's bind matches a scaled-down rig.
g.doc["skins"][0]["inverseBindMatrices"] = g.accessor(
    [translation_matrix([0, 0, 0]), translation_matrix([0, -0.5, 0])], "MAT4")
g.doc["nodes"][spine]["translation"] = [0, 0.5, 0]
g.doc["scenes"][0]["nodes"] = [hips, body]
g.doc["extensionsUsed"] = ["KHR_mesh_quantization"]
g.doc["extensionsRequired"] = ["KHR_mesh_quantization"]
animate(g, [(spine, "rotation", [0.0, 0.5, 1.0], [quat_z(0), quat_z(0), quat_z(0)])])
sparse_values = g.accessor([quat_z(70)], "VEC4")
sparse_indices = g.accessor([1], "SCALAR", 5123)
out = g.doc["animations"][0]["samplers"][0]["output"]
g.doc["accessors"][out]["sparse"] = {
    "count": 1, "indices": {"bufferView": g.doc["accessors"][sparse_indices]["bufferView"], "componentType": 5123},
    "values": {"bufferView": g.doc["accessors"][sparse_values]["bufferView"]}}
generated.append((g.save("quantised_sparse.gltf"), None))
# Eight influences per vertex over eight joints (a chain), in JOINTS_0/1 and WEIGHTS_0/1.
g = Gltf()
chain = []
for j in range(8):
    chain.append(g.node(name="j%d" % j, translation=[0, 0 if j == 0 else 0.25, 0]))
for j in range(7):
    g.doc["nodes"][chain[j]]["children"] = [chain[j + 1]]
ibms = [translation_matrix([0, -0.25 * j, 0]) for j in range(8)]
g.doc["skins"].append({"joints": chain, "inverseBindMatrices": g.accessor(ibms, "MAT4")})


def eight_weights(r, x):
    raw = [1.0 + ((r * 3 + j * 5 + (x > 0)) % 7) for j in range(8)]
    total = sum(raw)
    w = [v / total for v in raw]
    return [w[0:4], w[4:8]]


g.doc["meshes"].append({"name": "eight", "primitives": [
    bar(g, influences=(lambda r, x: [[0, 1, 2, 3], [4, 5, 6, 7]], eight_weights))]})
body = g.node(name="body", mesh=0, skin=0)
g.doc["scenes"][0]["nodes"] = [chain[0], body]
animate(g, [(chain[j], "rotation", [0.0, 1.0], [quat_z(0), quat_z(10 + 5 * j)]) for j in range(1, 8)])
generated.append((g.save("eight_influences.gltf"), None))


def morph_skin(name, interpolation, sparse):
    """The two-joint bar with two morph targets (named by extras.targetNames; `bulge` moves the top rows only,
    `lean` every vertex, with normals), default weights [0.25, 0], a weights channel with `interpolation` beside a
    LINEAR spine rotation. `sparse`: `bulge` is a sparse accessor without a bufferView."""
    g = Gltf()
    hips, spine, skin = two_joint_rig(g)
    prim = bar(g)
    bulge_rows = [6, 7, 8, 9]
    bulge = [[0.3 * (1 if i % 2 else -1), 0.1, 0.2] for i in bulge_rows]
    if sparse:
        values = g.accessor(bulge, "VEC3")
        indices = g.accessor(bulge_rows, "SCALAR", 5123)
        a = {"componentType": 5126, "count": 10, "type": "VEC3", "min": [-0.3, 0, 0], "max": [0.3, 0.1, 0.2],
             "sparse": {"count": len(bulge_rows),
                        "indices": {"bufferView": g.doc["accessors"][indices]["bufferView"], "componentType": 5123},
                        "values": {"bufferView": g.doc["accessors"][values]["bufferView"]}}}
        g.doc["accessors"].append(a)
        bulge_target = len(g.doc["accessors"]) - 1
    else:
        dense = [[0, 0, 0]] * 10
        for i, d in zip(bulge_rows, bulge):
            dense[i] = d
        bulge_target = g.accessor(dense, "VEC3", minmax=True)
    lean = g.accessor([[0.05 * (i // 2), 0.0, -0.1] for i in range(10)], "VEC3", minmax=True)
    prim["targets"] = [{"POSITION": bulge_target}, {"POSITION": lean}]
    g.doc["meshes"].append({"name": "bar", "primitives": [prim], "weights": [0.25, 0.0],
                            "extras": {"targetNames": ["bulge", "lean"]}})
    body = g.node(name="body", mesh=0, skin=skin)
    g.doc["scenes"][0]["nodes"] = [hips, body]
    animate(g, [(spine, "rotation", [0.0, 0.5, 1.0], [quat_z(0), quat_z(35), quat_z(-20)])])
    times = [0.0, 0.6, 1.0]
    keys = [[0.0, 0.0], [1.0, 0.5], [0.2, 1.0]]
    if interpolation == "CUBICSPLINE":
        tangents = [[0.5, -1.0], [0.0, 2.0], [-1.0, 0.3]]
        out = []
        for key, tangent in zip(keys, tangents):
            out += tangent + key + [-t for t in tangent]
    else:
        out = [w for key in keys for w in key]
    sampler = {"input": g.accessor(times, "SCALAR"), "interpolation": interpolation, "output": g.accessor(out, "SCALAR")}
    g.doc["accessors"][sampler["input"]].update({"min": [0.0], "max": [1.0]})
    g.doc["animations"][0]["samplers"].append(sampler)
    g.doc["animations"][0]["channels"].append(
        {"sampler": len(g.doc["animations"][0]["samplers"]) - 1, "target": {"node": body, "path": "weights"}})
    return g.save(name)


generated.append((morph_skin("morph_skin_linear.gltf", "LINEAR", False), None))
generated.append((morph_skin("morph_skin_step_sparse.gltf", "STEP", True), None))
generated.append((morph_skin("morph_skin_cubic.gltf", "CUBICSPLINE", True), None))

# `deform export --format gltf` of the eight-influence import writes the extras as JOINTS_1 / WEIGHTS_1: it skins as
# three.js skins the original (the exported clip is named as the import's).
exported = os.path.join(work, "eight_exported.gltf")
p = subprocess.run([deform, "export", os.path.join(work, "eight_influences.gltf"), "--format", "gltf", "--out", exported],
                   capture_output=True, text=True, timeout=120)
if p.returncode != 0:
    failures.append("deform export eight_influences.gltf --format gltf: exit %d, %s" % (p.returncode, p.stderr.strip()))
else:
    generated.append((exported, None))
    v = subprocess.run(["node", os.path.join(node_dir, "validate_gltf.js"), exported], capture_output=True, text=True,
                       timeout=120)
    report = json.loads(v.stdout.splitlines()[0]) if v.returncode == 0 and v.stdout.strip() else {"errors": "?"}
    if report.get("errors") != 0:
        failures.append("eight_exported.gltf: the Khronos validator reports %s errors: %s" %
                        (report.get("errors"), report.get("messages", v.stderr.strip())))
# `deform export` to the native files (.skw holds four influences) says what it drops.
p = subprocess.run([deform, "export", os.path.join(work, "eight_influences.gltf"), "--out", os.path.join(work, "native")],
                   capture_output=True, text=True, timeout=120)
if p.returncode != 0 or "more than 4 influences, more than .skw readers keep by default" not in p.stderr:
    failures.append("deform export eight_influences.gltf (native): exit %d, no .skw warning: %s" %
                    (p.returncode, p.stderr.strip()))

for path, _ in generated:
    compare(os.path.basename(path), path)
# --morph overrides a target's weight, as three's morphTargetInfluences does, over the clip's animated weights.
compare("morph_skin_linear.gltf --morph", os.path.join(work, "morph_skin_linear.gltf"),
        morphs={"bulge": 0.7, "lean": -0.4})
p = subprocess.run([deform, "skin", os.path.join(work, "morph_skin_linear.gltf"), "--out", os.path.join(work, "x.obj"),
                    "--clip", "move", "--time", "0.2", "--morph", "nose:1"], capture_output=True, text=True, timeout=120)
if p.returncode != 2 or "nose" not in p.stderr:
    failures.append("deform skin --morph nose:1 (no such target): exit %d, %s" % (p.returncode, p.stderr.strip()))
for bad, says in (("bulge", "is not NAME:WEIGHT"), ("bulge:nan", "is not a finite number"),
                  ("bulge:1e39", "out of float range"), ("bulge:1,", "is not NAME:WEIGHT")):
    p = subprocess.run([deform, "skin", os.path.join(work, "morph_skin_linear.gltf"), "--out", os.path.join(work, "x.obj"),
                        "--clip", "move", "--time", "0.2", "--morph", bad], capture_output=True, text=True, timeout=120)
    if p.returncode != 2 or says not in p.stderr:
        failures.append("deform skin --morph %s: exit %d, %s" % (bad, p.returncode, p.stderr.strip()))

# `deform info` names the samplers each clip uses.
for name, expected in (("step.gltf", ["step"]), ("cubic.gltf", ["cubic_spline"]), ("two_rigs.gltf", ["linear"])):
    p = subprocess.run([deform, "info", os.path.join(work, name)], capture_output=True, text=True, timeout=120)
    got = [c.get("interpolation") for c in json.loads(p.stdout).get("clips", [])] if p.returncode == 0 else p.stderr
    if got != [expected]:
        failures.append("deform info %s: clip interpolation %s, expected %s" % (name, got, [expected]))

# `deform info` lists the morph targets (name, mesh) and the most influences a point has.
for name, targets, most in (("morph_skin_linear.gltf", [["bulge", "bar"], ["lean", "bar"]], 2),
                            ("eight_influences.gltf", [], 8)):
    p = subprocess.run([deform, "info", os.path.join(work, name)], capture_output=True, text=True, timeout=120)
    got = json.loads(p.stdout) if p.returncode == 0 else {}
    listed = [[t.get("name"), t.get("mesh")] for t in got.get("morph_targets", [])]
    if listed != targets or got.get("max_influences") != most:
        failures.append("deform info %s: morph_targets %s, max_influences %s; expected %s, %d" %
                        (name, listed, got.get("max_influences"), targets, most))

# --- the glTF 2.0 models Debian's assimp-testmodels ships ---
for path in sorted(glob.glob(os.path.join(models, "glTF2", "**", "*.gl*"), recursive=True)):
    if not path.endswith((".gltf", ".glb")):
        continue
    # Several are malformed on purpose (indices out of range, infinite positions, only points or lines): libdeform
    # refuses those with a message, which is listed; a file it reads must agree.
    compare(os.path.relpath(path, models), path, may_refuse=True)

for line in results:
    print(line)
for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
