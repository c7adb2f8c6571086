#!/usr/bin/env python3
"""`deform export --format gltf --rig RIG` (docs/gltf-export.md, "Pose-space correctives"): a rig's correctives as
morph targets of a skinned file, their drivers' weights keyed per clip, played by three.js.
  - the built-in character with an elbow pad on the left forearm (a corrective sculpted at the elbow bent 100°): the
    file passes the Khronos validator with no error or warning, names the target, and every clip has a `weights`
    channel keyed 30 times a second (--fps 20: 20);
  - three.js (tests/node/three_skin.mjs) plays the run out of that file at every key time, and the morph bake of the
    same run with the same rig (`deform bake`, which records the points libdeform deforms): every triangle corner
    agrees within 1e-5 of the diagonal. The same export without the rig puts the padded corners up to about the
    pad's 1 cm away, so a weights channel written wrong, or not at all, fails here;
  - --fps 0, --fps without --rig and --rig with the native format exit 2 and write nothing.
Usage: export_correctives_test.py DEFORM NODE_DIR WORK_DIR. Exits 77 (skipped) when node, three.js or the validator
is missing (scripts/test installs them)."""
import json, math, os, shutil, struct, subprocess, sys

deform, node_dir, work = sys.argv[1:4]
if shutil.which("node") is None or not all(
        os.path.isdir(os.path.join(node_dir, "node_modules", m)) for m in ("three", "gltf-validator")):
    print("skipped: node, three.js or gltf-validator missing (npm ci --prefix tests/node)")
    sys.exit(77)
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def run(*args, expect=0):
    p = subprocess.run([deform, *args], capture_output=True, text=True, cwd=work, timeout=600)
    if p.returncode != expect:
        check(False, f"{' '.join(args)}: exit {p.returncode}, expected {expect}: {p.stderr.strip()}")
        return None
    return json.loads(p.stdout) if expect == 0 else p.stderr


def gltf_json(path):
    data = open(path, "rb").read()
    length = struct.unpack_from("<I", data, 12)[0]
    return json.loads(data[20:20 + length])


def three(path, animation=None, times=None):
    args = ["node", os.path.join(node_dir, "three_skin.mjs"), path]
    if times:
        args += [str(animation), ",".join(map(repr, times))]
    p = subprocess.run(args, capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        check(False, f"three.js on {os.path.basename(path)}: {p.stderr.strip()[-300:]}")
        return None
    result = json.loads(p.stdout)
    return result["frames"] if times else result["corners"]


def validate(path):
    p = subprocess.run(["node", os.path.join(node_dir, "validate_gltf.js"), path], capture_output=True, text=True,
                       timeout=300)
    report = json.loads(p.stdout.splitlines()[0]) if p.returncode == 0 and p.stdout else None
    check(report is not None and report["errors"] == 0 and report["warnings"] == 0,
          f"validator on {os.path.basename(path)}: {report['messages'][:3] if report else p.stderr.strip()}")


# An elbow pad: three points of the left forearm pushed out 1 cm, sculpted with the elbow bent 100° about x.
rig = {"rig": 1, "lattices": [], "correctives": [{"name": "elbow", "bones": ["forearm_l"], "shapes": [
    {"name": "elbow_pad", "pose": [[100, 0, 0]], "points": [1, 5, 9],
     "deltas": [[0, 0, 0.01], [0, 0.01, 0], [0.01, 0, 0]]}]}]}
with open(os.path.join(work, "pad.rig.json"), "w") as f:
    json.dump(rig, f)

padded = run("export", "--builtin", "--rig", "pad.rig.json", "--format", "gltf", "--out", "padded.glb")
plain = run("export", "--builtin", "--format", "gltf", "--out", "plain.glb")
slow = run("export", "--builtin", "--rig", "pad.rig.json", "--format", "gltf", "--fps", "20", "--out", "slow.gltf")
if padded and plain and slow:
    check(padded.get("morph_targets") == 1 and "morph_targets" not in plain,
          f"morph_targets reported: {padded.get('morph_targets')}, {plain.get('morph_targets')}")
    validate(os.path.join(work, "padded.glb"))
    validate(os.path.join(work, "slow.gltf"))
    doc = gltf_json(os.path.join(work, "padded.glb"))
    check(doc["meshes"][0].get("extras", {}).get("targetNames") == ["elbow_pad"], "the target is not named")
    slow_doc = json.load(open(os.path.join(work, "slow.gltf")))
    for d, fps in ((doc, 30), (slow_doc, 20)):
        for animation in d["animations"]:
            weights = [c for c in animation["channels"] if c["target"]["path"] == "weights"]
            check(len(weights) == 1, f"clip {animation.get('name')}: {len(weights)} weights channels")
            if weights:
                keys = d["accessors"][animation["samplers"][weights[0]["sampler"]]["input"]]
                expected = math.floor(keys["max"][0] * fps - 1e-3) + 2  # k / fps before the duration, then it
                check(keys["count"] == expected and keys["min"][0] == 0,
                      f"clip {animation.get('name')} at {fps} fps: {keys['count']} keys, expected {expected}")
    names = [a.get("name") for a in doc["animations"]]
    report = run("bake", "--builtin", "--rig", "pad.rig.json", "--clip", "run", "--out", "run-bake.glb")
    if "run" in names and report:
        times = [k / report["fps"] for k in range(report["frames"])]
        played = three(os.path.join(work, "padded.glb"), names.index("run"), times)
        unpadded = three(os.path.join(work, "plain.glb"), names.index("run"), times)
        baked = three(os.path.join(work, "run-bake.glb"), 0, times)
        rest = three(os.path.join(work, "plain.glb"))
        if played and unpadded and baked and rest:
            lo = [min(p[i] for p in rest) for i in range(3)]
            hi = [max(p[i] for p in rest) for i in range(3)]
            size = math.dist(lo, hi)
            worst = max(max(math.dist(a, b) for a, b in zip(f, g)) for f, g in zip(played, baked))
            pad = max(max(math.dist(a, b) for a, b in zip(f, g)) for f, g in zip(unpadded, baked))
            check(worst <= 1e-5 * size, f"three.js puts a corner {worst:.2e} from the bake (allowed {1e-5 * size:.2e})")
            check(pad > 0.005, f"without the rig the corners are only {pad:.4f} from the bake: the pad never shows")
            print(f"run: {len(times)} frames, the export {worst:.2e} from the bake, without the rig {pad:.4f}")

for args in (("--rig", "pad.rig.json", "--format", "gltf", "--fps", "0", "--out", "bad.glb"),
             ("--format", "gltf", "--fps", "20", "--out", "bad.glb"),
             ("--rig", "pad.rig.json", "--out", "bad")):
    run("export", "--builtin", *args, expect=2)
check(not os.path.exists(os.path.join(work, "bad.glb")) and not os.path.exists(os.path.join(work, "bad")),
      "a refused export wrote a file")

if failures:
    print(f"{len(failures)} checks failed")
    sys.exit(1)
print("export with correctives: every check passed")
