#!/usr/bin/env python3
"""deform ik end to end: solves, output contract, the reported effector equals FK of the reported angles, exit codes.

usage: ik_cli_test.py DEFORM_EXE WORK_DIR
FK here is written independently of libdeform from docs/formats.md: L = T(t) · Rx · Ry · Rz, W = W_parent · L.
"""
import json, math, os, struct, subprocess, sys

exe, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
failures = []


def check(condition, what):
    if not condition:
        failures.append(what)
        print("FAIL:", what)


# --- a small arm: base -> shoulder -> elbow -> wrist -> hand, plus a sibling ---
FREE = ((-180, 180), (-180, 180), (-180, 180))
BONES = [  # name, parent, translation, rotation, limits ((min,max) per axis)
    ("base", -1, (0, 0, 0), (0, 0, 0), FREE),
    ("shoulder", 0, (0, 1, 0), (0, 0, 0), FREE),
    ("elbow", 1, (1, 0, 0), (0, 0, 0), ((-90, 90), (-150, 0), (-90, 90))),
    ("wrist", 2, (1, 0, 0), (0, 0, 0), FREE),
    ("hand", 3, (0.5, 0, 0), (0, 0, 0), FREE),
    ("head", 0, (0, 1.5, 0), (0, 0, 0), FREE),
]


def write_sk(path):
    data = b"SKEL" + struct.pack("<i", len(BONES))
    for i, (name, parent, t, r, lim) in enumerate(BONES):
        children = [j for j, b in enumerate(BONES) if b[1] == i]
        data += name.encode().ljust(80, b"\0") + struct.pack("<6f", *t, *r)
        data += struct.pack("<6f", lim[0][1], lim[0][0], lim[1][1], lim[1][0], lim[2][1], lim[2][0])
        data += struct.pack("<ii", parent, len(children)) + struct.pack("<%di" % len(children), *children)
    with open(path, "wb") as f:
        f.write(data)


def qmul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def qrot(q, v):
    w, x, y, z = qmul(qmul(q, (0.0, *v)), (q[0], -q[1], -q[2], -q[3]))
    return (x, y, z)


def q_euler(e):
    h = [math.radians(a) / 2 for a in e]
    return qmul(qmul((math.cos(h[0]), math.sin(h[0]), 0, 0), (math.cos(h[1]), 0, math.sin(h[1]), 0)),
                (math.cos(h[2]), 0, 0, math.sin(h[2])))


def head_of(name, pose):
    """World head of a bone; pose: name -> {rotation, translation}, else bind values."""
    chain = []
    i = [b[0] for b in BONES].index(name)
    while i >= 0:
        chain.append(i)
        i = BONES[i][1]
    q, p = (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    for i in reversed(chain):
        name_i, _, t, r, _ = BONES[i]
        entry = pose.get(name_i, {})
        t = entry.get("translation", t)
        r = entry.get("rotation", r)
        p = tuple(a + b for a, b in zip(p, qrot(q, t)))
        q = qmul(q, q_euler(r))
    return p


def run(*args):
    proc = subprocess.run([exe, "ik", *args], capture_output=True, text=True, timeout=60)
    return proc.returncode, proc.stdout, proc.stderr


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


sk = os.path.join(work, "arm.sk")
write_sk(sk)
LENGTH = 2.5  # shoulder -> hand

for solver, root in (("ccd", "shoulder"), ("fabrik", "shoulder"), ("two-bone", "elbow")):
    target = (1.2, 1.9, 0.6) if root == "shoulder" else (1.4, 1.3, 0.2)
    code, out, err = run(sk, "--effector", "hand", "--target", ",".join(map(str, target)), "--root", root,
                         "--solver", solver)
    check(code == 0, f"{solver}: exit {code} ({err.strip()})")
    if code != 0:
        continue
    doc = json.loads(out)
    check(list(doc) == ["solver", "reached", "distance", "iterations", "effector", "bones"], f"{solver}: keys {list(doc)}")
    check(doc["solver"] == solver, f"{solver}: solver field")
    check(doc["reached"] is True, f"{solver}: reached {doc['reached']} distance {doc['distance']}")
    check(doc["distance"] <= 1e-3, f"{solver}: distance {doc['distance']}")
    check(dist(doc["effector"], target) <= 1e-3, f"{solver}: effector {doc['effector']} vs target {target}")
    check(abs(dist(doc["effector"], target) - doc["distance"]) <= 1e-5, f"{solver}: distance is |effector - target|")
    chain = ["shoulder", "elbow", "wrist", "hand"] if root == "shoulder" else ["elbow", "wrist", "hand"]
    check(list(doc["bones"]) == chain, f"{solver}: bones {list(doc['bones'])}")
    # Feed the printed bones back through an independent FK: the effector the tool reports.
    fk = head_of("hand", doc["bones"])
    check(dist(fk, doc["effector"]) <= 1e-4, f"{solver}: FK of printed bones {fk} vs effector {doc['effector']}")
    elbow = doc["bones"]["elbow"]["rotation"]
    check(-150 - 1e-3 <= elbow[1] <= 1e-3, f"{solver}: elbow y {elbow[1]} outside its limits")
    check(1 <= doc["iterations"] <= 100, f"{solver}: iterations {doc['iterations']}")

# Unreachable: not an error; the closest pose, the straight arm pointing at the target.
code, out, err = run(sk, "--effector", "hand", "--target", "10,1,0", "--root", "shoulder", "--max-iterations", "300")
check(code == 0, f"unreachable: exit {code} ({err.strip()})")
if code == 0:
    doc = json.loads(out)
    check(doc["reached"] is False, "unreachable: reached must be false")
    best = dist((10, 1, 0), (0, 1, 0)) - LENGTH
    check(abs(doc["distance"] - best) <= 1e-3, f"unreachable: distance {doc['distance']} vs {best}")
    check(dist(head_of("hand", doc["bones"]), doc["effector"]) <= 1e-4, "unreachable: FK of printed bones")

# --tolerance and --max-iterations are honoured.
code, out, _ = run(sk, "--effector", "hand", "--target", "0.3,2.2,1.4", "--max-iterations", "1", "--tolerance", "0")
check(code == 0 and json.loads(out)["iterations"] == 1, "--max-iterations 1 gives one iteration")

# Bad usage and invalid input: exit 2, message on stderr, nothing on stdout.
for args, what in (
    ((sk, "--effector", "nope", "--target", "1,1,1"), "unknown effector"),
    ((sk, "--effector", "hand", "--target", "1,1"), "target with two numbers"),
    ((sk, "--effector", "hand", "--target", "nan,0,0"), "non-finite target"),
    ((sk, "--effector", "hand", "--target", "1,inf,0"), "infinite target"),
    ((sk, "--target", "1,1,1"), "missing --effector"),
    ((sk, "--effector", "hand"), "missing --target"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--root", "head"), "root not an ancestor"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--solver", "two-bone", "--root", "shoulder"), "two-bone on 3 joints"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--solver", "magic"), "unknown solver"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--max-iterations", "0"), "zero iterations"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--tolerance", "-1"), "negative tolerance"),
    ((os.path.join(work, "missing.sk"), "--effector", "hand", "--target", "1,1,1"), "missing file"),
    (("--effector", "hand", "--target", "1,1,1"), "no skeleton"),
):
    code, out, err = run(*args)
    check(code == 2 and out == "" and err != "", f"{what}: exit {code}, stdout {out!r}")

# A truncated .sk is invalid input, not a crash.
with open(sk, "rb") as f:
    data = f.read()
bad = os.path.join(work, "truncated.sk")
with open(bad, "wb") as f:
    f.write(data[:100])
code, out, err = run(bad, "--effector", "hand", "--target", "1,1,1")
check(code == 2 and "truncated.sk" in err, f"truncated file: exit {code}, {err.strip()}")

# The built-in character.
code, out, err = run("--builtin", "--effector", "hand_l", "--root", "upperarm_l", "--target", "0.6,1.3,0.2")
check(code == 0, f"--builtin: exit {code} ({err.strip()})")
if code == 0:
    doc = json.loads(out)
    check(list(doc["bones"]) == ["upperarm_l", "forearm_l", "hand_l"], f"--builtin: bones {list(doc['bones'])}")
    check(doc["distance"] >= 0 and len(doc["effector"]) == 3, "--builtin: output")

# --- two-bone rig settings: shoulder (head (0, 1, 0)) -> elbow -> wrist, both bones of length 1, the elbow bending
# about its -y (toward +z of the shoulder's frame) within its limits.
SHOULDER = (0.0, 1.0, 0.0)


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def across(v, d):  # the part of v across the unit direction d
    k = dot(v, d)
    return tuple(x - k * y for x, y in zip(v, d))


def unit(v):
    n = math.sqrt(dot(v, v))
    return tuple(x / n for x in v)


def two_bone(target, *flags):
    code, out, err = run(sk, "--effector", "wrist", "--root", "shoulder", "--solver", "two-bone", "--target",
                         ",".join(map(str, target)), *flags)
    check(code == 0, f"two-bone {flags}: exit {code} ({err.strip()})")
    return json.loads(out) if code == 0 else None


# --pole (a world point): the elbow lies in the plane of shoulder, target and pole, on the pole's side; --swivel 90
# turns it a quarter turn about shoulder -> target (right-handed).
target, pole = (1.2, 1.9, 0.6), (0.5, 1.0, 2.0)
d = unit(sub(target, SHOULDER))
pole_across = unit(across(sub(pole, SHOULDER), d))
for swivel, expected in ((None, pole_across), ("90", cross(d, pole_across))):
    flags = ("--pole", "0.5,1,2") + (("--swivel", swivel) if swivel else ())
    doc = two_bone(target, *flags)
    if doc:
        check(doc["reached"] is True, f"two-bone {flags}: reached {doc['reached']} distance {doc['distance']}")
        elbow = across(sub(head_of("elbow", doc["bones"]), SHOULDER), d)
        check(dot(unit(elbow), expected) > 1 - 1e-6, f"two-bone {flags}: elbow direction {unit(elbow)} vs {expected}")
        check(dist(head_of("wrist", doc["bones"]), target) <= 1e-4, f"two-bone {flags}: FK of printed bones")
        check("stretch" not in doc, f"two-bone {flags}: no stretch key without --stretch")

# --soften: a target at full reach (2 from the shoulder) is met without it and falls short by soften x 2 / e with it.
full = (SHOULDER[0] + 1.2, SHOULDER[1] + 1.6, 0.0)
previous = 0.0
for soften in ("0", "0.1", "0.2"):
    doc = two_bone(full, "--pole", "0,1,1", "--soften", soften)
    if doc:
        expected = float(soften) * 2.0 / math.e
        check(abs(doc["distance"] - expected) <= 1e-4, f"--soften {soften}: distance {doc['distance']} vs {expected}")
        check(doc["reached"] is (soften == "0"), f"--soften {soften}: reached {doc['reached']}")
        check(doc["distance"] >= previous, f"--soften {soften}: farther than a smaller soften")
        previous = doc["distance"]

# --stretch: 2.6 from the shoulder needs 1.3; up to 1.5 it reaches with both bones 1.3 long (the printed
# translations carry it), with 1.2 it stops 0.2 short.
far = (SHOULDER[0] + 1.56, SHOULDER[1] + 2.08, 0.0)
for max_stretch, factor, distance in (("1.5", 1.3, 0.0), ("1.2", 1.2, 0.2)):
    doc = two_bone(far, "--pole", "0,1,1", "--stretch", max_stretch)
    if doc:
        check(list(doc) == ["solver", "reached", "distance", "iterations", "stretch", "effector", "bones"],
              f"--stretch: keys {list(doc)}")
        check(abs(doc["stretch"] - factor) <= 1e-5, f"--stretch {max_stretch}: stretch {doc['stretch']} vs {factor}")
        check(abs(doc["distance"] - distance) <= 1e-4, f"--stretch {max_stretch}: distance {doc['distance']}")
        check(doc["reached"] is (distance == 0.0), f"--stretch {max_stretch}: reached {doc['reached']}")
        for bone in ("elbow", "wrist"):
            length = math.sqrt(dot(doc["bones"][bone]["translation"], doc["bones"][bone]["translation"]))
            check(abs(length - factor) <= 1e-5, f"--stretch {max_stretch}: {bone} translation length {length}")
        check(dist(head_of("wrist", doc["bones"]), doc["effector"]) <= 1e-4, f"--stretch {max_stretch}: FK of bones")

# The rig flags are the two-bone solver's: another solver, or a value out of range, is exit 2.
for args, what in (
    (("--pole", "1,1,1"), "--pole with ccd"),
    (("--solver", "fabrik", "--soften", "0.1"), "--soften with fabrik"),
    (("--stretch", "2"), "--stretch with ccd"),
    (("--solver", "two-bone", "--root", "shoulder", "--soften", "1.5"), "--soften above 1"),
    (("--solver", "two-bone", "--root", "shoulder", "--soften", "-0.1"), "--soften below 0"),
    (("--solver", "two-bone", "--root", "shoulder", "--stretch", "0.5"), "--stretch below 1"),
    (("--solver", "two-bone", "--root", "shoulder", "--stretch", "inf"), "--stretch infinite"),
    (("--solver", "two-bone", "--root", "shoulder", "--swivel", "400"), "--swivel beyond 360"),
    (("--solver", "two-bone", "--root", "shoulder", "--pole", "1,nan,0"), "--pole not finite"),
    (("--solver", "two-bone", "--root", "shoulder", "--pole", "1,1"), "--pole with two numbers"),
):
    code, out, err = run(sk, "--effector", "wrist", "--target", "1,1,1", *args)
    check(code == 2 and out == "" and err != "", f"{what}: exit {code}, stdout {out!r}, stderr {err.strip()!r}")

print("ik CLI:", "FAILED" if failures else "ok", f"({len(failures)} failures)")
sys.exit(1 if failures else 0)
