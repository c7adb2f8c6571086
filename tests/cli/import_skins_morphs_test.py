#!/usr/bin/env python3
"""`deform info` lists an import's skins and `deform skin --blend` blends the clips' morph weights, end to end on glTF
files written here (and Testwuson.X from Debian's assimp-testmodels, when installed):
  - info: a glTF file with three skins (two meshes on the first, one on the second, one unused) lists all three with
    their names, joint counts and meshes, and every bone (`skeleton`: ids, parents, bind-pose heads); an Assimp
    format lists one skin; a static file has no "skins" or "skeleton" key;
  - skin --blend: two clips that animate only morph weights give, blended a:1,b:3, the points of --clip a with the
    weights set to their weighted average by --morph; below a summed weight of 0.1 the defaults join in (as the bind
    pose does for the poses); --morph still overrides a blended weight.
Usage: import_skins_morphs_test.py DEFORM WORK_DIR [ASSIMP_MODELS]"""
import base64, json, math, os, shutil, struct, subprocess, sys

deform, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
models = sys.argv[3] if len(sys.argv) > 3 else ""
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
    return condition


def run(*args):
    p = subprocess.run([deform, *args], capture_output=True, text=True, timeout=300, cwd=work)
    return p.returncode, p.stdout, p.stderr


class Gltf:
    """One buffer (a data URI); accessors of float32 (or the given format) appended."""

    def __init__(self):
        self.blob = b""
        self.doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}], "nodes": [], "meshes": [],
                    "bufferViews": [], "accessors": []}

    def accessor(self, values, kind, component=5126, fmt="f", extra=None):
        while len(self.blob) % 4:
            self.blob += b"\0"
        data = struct.pack("<%d%s" % (len(values), fmt), *values)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)})
        self.blob += data
        width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}[kind]
        a = {"bufferView": len(self.doc["bufferViews"]) - 1, "componentType": component,
             "count": len(values) // width, "type": kind}
        a.update(extra or {})
        self.doc["accessors"].append(a)
        return len(self.doc["accessors"]) - 1

    def bar(self, x0=0.0, targets=None):
        """A bar of 5 rows × 2 points from y 0 to 2, skinned to joints 0 and 1 of its skin (1 above y 0.5)."""
        pos, joints, weights = [], [], []
        for r in range(5):
            for s in range(2):
                pos += [x0 + (0.2 if s else -0.2), 0.5 * r, 0.0]
                w = min(max(0.5 * r - 0.5, 0.0), 1.0)
                joints += [0, 1, 0, 0]
                weights += [1 - w, w, 0, 0]
        xs = pos[0::3]
        prim = {"attributes": {
            "POSITION": self.accessor(pos, "VEC3", extra={"min": [min(xs), 0, 0], "max": [max(xs), 2, 0]}),
            "JOINTS_0": self.accessor(joints, "VEC4", 5121, "B"),
            "WEIGHTS_0": self.accessor(weights, "VEC4")},
            "indices": self.accessor([i for r in range(4) for i in (2 * r, 2 * r + 1, 2 * r + 3, 2 * r, 2 * r + 3,
                                                                     2 * r + 2)], "SCALAR", 5123, "H")}
        if targets:
            prim["targets"] = [{"POSITION": self.accessor(t, "VEC3", extra={
                "min": [min(t[i::3]) for i in range(3)], "max": [max(t[i::3]) for i in range(3)]})} for t in targets]
        return prim

    def node(self, **fields):
        self.doc["nodes"].append(fields)
        return len(self.doc["nodes"]) - 1

    def save(self, name):
        self.doc["buffers"] = [{"byteLength": len(self.blob),
                                "uri": "data:application/octet-stream;base64," + base64.b64encode(self.blob).decode()}]
        path = os.path.join(work, name)
        with open(path, "w") as f:
            json.dump(self.doc, f)
        return path


def info(path):
    rc, out, err = run("info", path)
    if not check(rc == 0, f"info {path}: exit {rc}: {err}"):
        return {}
    return json.loads(out)


# --- info: three skins, two used ---
g = Gltf()
hips = g.node(name="hips", children=[1])
g.node(name="spine", translation=[0, 1, 0])
g.doc["meshes"].append({"name": "bar", "primitives": [g.bar()]})
g.doc["meshes"].append({"primitives": [g.bar(x0=3.0)]})  # unnamed: listed by its JSON path
body = g.node(name="body", mesh=0, skin=0)
body2 = g.node(name="body2", mesh=0, skin=0)
base = g.node(name="base", translation=[3, 0, 0], children=[5])
g.node(name="tip", translation=[0, 1, 0])
pole = g.node(name="pole", mesh=1, skin=1)
ibm = g.accessor([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1], "MAT4")
ibm2 = g.accessor([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -3, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -3, -1, 0, 1],
                  "MAT4")
g.doc["skins"] = [{"name": "main", "joints": [hips, 1], "inverseBindMatrices": ibm},
                  {"name": "second", "joints": [base, 5], "inverseBindMatrices": ibm2},
                  {"name": "spare", "joints": [hips]}]
g.doc["scenes"][0]["nodes"] = [hips, body, body2, base, pole]
got = info(g.save("three_skins.gltf"))
expected = [{"name": "main", "joints": 2, "meshes": ["bar"]}, {"name": "second", "joints": 2, "meshes": ["meshes[1]"]},
            {"name": "spare", "joints": 1, "meshes": []}]
check(got.get("skins") == expected, f"info three_skins.gltf: skins {got.get('skins')}, expected {expected}")
for key in ("kind", "vertices", "triangles", "materials", "bones"):
    check(key in got, f"info three_skins.gltf: the fixed key {key} is missing")
# "skeleton": every imported bone as a .sk's info lists it, parents before children, heads in the bind pose.
bones = got.get("skeleton", [])
by_name = {b["name"]: b for b in bones}
check(len(bones) == got.get("bones") and [b["id"] for b in bones] == list(range(len(bones))),
      f"info three_skins.gltf: skeleton {bones} against bones {got.get('bones')}")
check(all(-1 <= b["parent"] < b["id"] for b in bones), f"info three_skins.gltf: a parent after its child: {bones}")
check({"hips", "spine", "base", "tip"} <= set(by_name), f"info three_skins.gltf: skeleton names {list(by_name)}")
if {"spine", "tip"} <= set(by_name):
    check(by_name["spine"]["head"] == [0.0, 1.0, 0.0] and by_name["tip"]["head"] == [3.0, 1.0, 0.0]
          and bones[by_name["spine"]["parent"]]["name"] == "hips",
          f"info three_skins.gltf: spine {by_name['spine']}, tip {by_name['tip']}")
    check(set(by_name["tip"]["limits"]) == {"min", "max"}, f"info three_skins.gltf: tip limits {by_name['tip']}")

# A static glTF file (no skin, no animation): no "skins" key.
s = Gltf()
s.doc["meshes"].append({"name": "plain", "primitives": [{"attributes": {"POSITION": s.accessor(
    [0, 0, 0, 1, 0, 0, 0, 1, 0], "VEC3", extra={"min": [0, 0, 0], "max": [1, 1, 0]})}}]})
s.doc["scenes"][0]["nodes"] = [s.node(name="plain", mesh=0)]
got = info(s.save("static.gltf"))
check("skins" not in got and "skeleton" not in got and got.get("kind") is not None, f"info static.gltf: {got}")

# An Assimp format: one skin, its joints the bones the meshes name.
wuson = os.path.join(models, "X", "Testwuson.X") if models else ""
if wuson and os.path.exists(wuson):
    got = info(wuson)
    skins = got.get("skins", [])
    check(len(skins) == 1 and skins[0]["joints"] > 1 and skins[0]["joints"] <= got.get("bones", 0) and skins[0]["meshes"],
          f"info Testwuson.X: skins {skins} (bones {got.get('bones')})")
else:
    print("Testwuson.X not installed: the Assimp info check skipped")

# --- skin --blend: the clips' morph weights averaged ---
m = Gltf()
hips = m.node(name="hips", children=[1])
m.node(name="spine", translation=[0, 1, 0])
bulge = [0.0] * 30
for p in range(6, 10):
    bulge[3 * p] = 0.3 if p % 2 else -0.3
    bulge[3 * p + 2] = 0.2
lean = [v for p in range(10) for v in (0.05 * (p // 2), 0.0, -0.1)]
m.doc["meshes"].append({"name": "bar", "primitives": [m.bar(targets=[bulge, lean])], "weights": [0.25, 0.0],
                        "extras": {"targetNames": ["bulge", "lean"]}})
body = m.node(name="body", mesh=0, skin=0)
m.doc["skins"] = [{"joints": [hips, 1], "inverseBindMatrices": m.accessor(
    [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1], "MAT4")}]
m.doc["scenes"][0]["nodes"] = [hips, body]
times = m.accessor([0.0, 1.0], "SCALAR", extra={"min": [0.0], "max": [1.0]})
m.doc["animations"] = []
for name, keys in (("a", [1.0, 0.0, 1.0, 0.0]), ("b", [0.0, 1.0, 0.0, 1.0])):
    m.doc["animations"].append({"name": name, "samplers": [{"input": times, "output": m.accessor(keys, "SCALAR")}],
                                "channels": [{"sampler": 0, "target": {"node": body, "path": "weights"}}]})
model = m.save("morph_clips.gltf")


def points(*args):
    out = f"out{len(os.listdir(work))}.obj"
    rc, stdout, stderr = run("skin", model, *args, "--out", out)
    if not check(rc == 0, f"skin {' '.join(args)}: exit {rc}: {stderr}"):
        return None
    with open(os.path.join(work, out)) as f:
        return [tuple(map(float, line.split()[1:4])) for line in f if line.startswith("v ")]


def same(label, a, b, tolerance=1e-6):
    if a is None or b is None:
        return
    check(len(a) == len(b) and max(math.dist(p, q) for p, q in zip(a, b)) < tolerance,
          f"{label}: differ by {max(math.dist(p, q) for p, q in zip(a, b)) if len(a) == len(b) else 'count'}")


blended = points("--blend", "a:1,b:3", "--time", "0.5")
same("--blend a:1,b:3", blended, points("--clip", "a", "--time", "0.5", "--morph", "bulge:0.25,lean:0.75"))
defaults = points("--clip", "a", "--time", "0.5", "--morph", "bulge:0.25,lean:0")
check(blended is not None and defaults is not None and
      max(math.dist(p, q) for p, q in zip(blended, defaults)) > 0.01, "--blend left the morph weights at their defaults")
# Below a sum of 0.1 the defaults [0.25, 0] join in with weight 0.1 - 0.05: (0.05·[1, 0] + 0.05·[0.25, 0]) / 0.1.
same("--blend a:0.05", points("--blend", "a:0.05", "--time", "0.5"),
     points("--clip", "a", "--time", "0.5", "--morph", "bulge:0.625,lean:0"))
same("--blend a:1,b:3 --morph lean:-0.5", points("--blend", "a:1,b:3", "--time", "0.5", "--morph", "lean:-0.5"),
     points("--clip", "a", "--time", "0.5", "--morph", "bulge:0.25,lean:-0.5"))

for f in failures:
    print("FAIL:", f)
print("import skins and morph blending:", "FAILED" if failures else "ok")
sys.exit(1 if failures else 0)
