#!/usr/bin/env python3
"""`deform corrective` (docs/cli.md): a sculpted pose made a pose-space corrective of a rig.
  - the built-in character's left elbow bent to 120° (`deform skin --pose`), a band of its points padded by 1 cm, made
    a corrective: the shape moves exactly the padded points, and the character built with the written rig gives the
    sculpt back at the pose (max_error, to 1e-5 m);
  - a second sculpt, at another pose, joins the same group, and the rig read back keeps both (the file names the
    built-in model);
  - a sculpt of another mesh, an unknown bone, a shape name used twice, a group with other bones and a second shape
    at a group's pose exit 2 and write nothing.
Usage: corrective_test.py DEFORM WORK_DIR"""
import json, os, shutil, subprocess, sys

deform, work = sys.argv[1], sys.argv[2]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def run(*args, expect=0):
    p = subprocess.run([deform, *args], capture_output=True, text=True, cwd=work, timeout=300)
    if p.returncode != expect:
        check(False, f"{' '.join(args)}: exit {p.returncode}, expected {expect}: {p.stderr.strip()}")
        return None
    return json.loads(p.stdout) if expect == 0 and p.stdout.strip() else p.stderr


def sculpt(source, target, band, lift):
    """Copies an OBJ, lifting by `lift` in y every vertex whose x is within `band` and y above 1.2; returns the count."""
    lifted, out = 0, []
    for line in open(os.path.join(work, source)).read().split("\n"):
        t = line.split()
        if t and t[0] == "v":
            x, y, z = map(float, t[1:4])
            if band[0] < x < band[1] and y > 1.2:
                y += lift
                lifted += 1
            line = "v %r %r %r" % (x, y, z)
        out.append(line)
    open(os.path.join(work, target), "w").write("\n".join(out))
    return lifted


with open(os.path.join(work, "bend.json"), "w") as f:
    f.write('{"bones": {"forearm_l": {"rotation": [120, 0, 0]}}}')
run("skin", "--builtin", "--pose", "bend.json", "--out", "posed.obj")
padded = sculpt("posed.obj", "pad.obj", (0.42, 0.50), 0.01)
check(padded > 10, f"the sculpt moved only {padded} points")
out = run("corrective", "--builtin", "--pose", "bend.json", "--sculpt", "pad.obj", "--bones", "upperarm_l,forearm_l",
          "--out", "arm.rig.json")
if out:
    check(out["points"] == padded, f"the shape moves {out['points']} points, the sculpt {padded}")
    check(out["max_error"] < 1e-5, f"the rig gives the sculpt back only to {out['max_error']:g} m")
    check(out["group"] == "upperarm_l+forearm_l" and out["shape"] == "pad" and out["shapes"] == 1, f"{out}")
# A second shape, at another pose, joins the group; the written rig keeps the first.
with open(os.path.join(work, "half.json"), "w") as f:
    f.write('{"bones": {"forearm_l": {"rotation": [60, 0, 0]}}}')
run("skin", "--builtin", "--pose", "half.json", "--out", "half.obj")
sculpt("half.obj", "pad2.obj", (0.30, 0.38), -0.005)
out = run("corrective", "arm.rig.json", "--pose", "half.json", "--sculpt", "pad2.obj", "--bones",
          "upperarm_l,forearm_l", "--out", "arm2.rig.json")
if out:
    check(out["shapes"] == 2 and out["max_error"] < 1e-5, f"second shape: {out}")
    rig = json.load(open(os.path.join(work, "arm2.rig.json")))
    check(rig["model"] == "builtin", f"the rig names {rig.get('model')}")
    shapes = [s["name"] for g in rig["correctives"] for s in g["shapes"]]
    check(shapes == ["pad", "pad2"], f"the rig's shapes are {shapes}")
# Refused, nothing written.
with open(os.path.join(work, "tiny.obj"), "w") as f:
    f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
for args in (["--sculpt", "tiny.obj", "--bones", "forearm_l"], ["--sculpt", "pad.obj", "--bones", "elbow_nowhere"],
             ["--sculpt", "pad.obj", "--bones", "forearm_l", "--group", "upperarm_l+forearm_l", "--name", "x"]):
    run("corrective", "arm.rig.json", "--pose", "bend.json", *args, "--out", "bad.rig.json", expect=2)
run("corrective", "arm.rig.json", "--pose", "bend.json", "--sculpt", "pad.obj", "--bones", "upperarm_l,forearm_l",
    "--out", "bad.rig.json", expect=2)  # "pad" is there already
run("corrective", "arm.rig.json", "--pose", "bend.json", "--sculpt", "pad2.obj", "--bones", "upperarm_l,forearm_l",
    "--name", "again", "--out", "bad.rig.json", expect=2)  # the group has a shape at this pose
check(not os.path.exists(os.path.join(work, "bad.rig.json")), "a refused command wrote bad.rig.json")

for f in failures:
    print("FAIL:", f)
sys.exit(1 if failures else 0)
