#!/usr/bin/env python3
"""`deform info MODEL --rig`: the default rig's choices and why, end to end on the rigged characters of Debian's
assimp-testmodels (each skipped when not installed):
  - mrfixit.iqm: the arms end at Hand.L / Hand.R and reach from the upper arms, not at the IK goals HandGoal.L /
    HandGoal.R (under ArmIK.L / ArmIK.R, under the spine), which are listed as left out with the reason; the legs
    reach from the thighs;
  - BCN_Epileptic.X: the arms reach from the clavicles, the legs from the hip joints, to the hands and ankles;
  - Testwuson.X: four-legged, four legs, a neck and a tail (a spring chain);
  - without --rig there is no "rig" key; --rig on a .sk is bad usage (exit 2), on a static model an error (exit 2).
Usage: info_rig_test.py DEFORM WORK_DIR MODELS_DIR"""
import json, os, shutil, subprocess, sys

deform, work, models = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]), sys.argv[3]
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


def rig_of(path):
    rc, out, err = run("info", path, "--rig")
    if not check(rc == 0, f"info {path} --rig: exit {rc}: {err}"):
        return None
    return json.loads(out)["rig"]


def limbs(rig):
    return [(l["kind"], l["side"], l["root"], l["effector"]) for l in rig["limbs"]]


tested = 0
mrfixit = os.path.join(models, "IQM/mrfixit.iqm")
if os.path.exists(mrfixit):
    tested += 1
    rig = rig_of(mrfixit)
    if rig:
        check(limbs(rig) == [("arm", "left", "UpperArm.L", "Hand.L"), ("arm", "right", "UpperArm.R", "Hand.R"),
                             ("leg", "left", "Thigh.L", "UpperFoot.L"), ("leg", "right", "Thigh.R", "UpperFoot.R")],
              f"mrfixit limbs: {limbs(rig)}")
        check(rig["reach"][0] == {"effector": "Hand.L", "root": "UpperArm.L"}, f"mrfixit reach: {rig['reach']}")
        check(not rig["four_legged"] and rig["up"] == [0, 0, 1], f"mrfixit body: {rig['four_legged']} {rig['up']}")
        skipped = {s["bone"]: s["why"] for s in rig["skipped"]}
        check("IK set-up" in skipped.get("ArmIK.L", "") and "IK set-up" in skipped.get("ArmIK.R", "") and
              "Hand.L" not in skipped, f"mrfixit skipped: {skipped}")
        check("no vertex" in skipped.get("ElbowRot.L", ""), f"mrfixit pole ElbowRot.L: {skipped}")
        check(all(l["why"] for l in rig["limbs"]), "every limb says why")
        check("HandGoal.L" not in rig["lattices"] and "Spine1" not in rig["lattices"] and "Hips" not in rig["lattices"],
              f"mrfixit lattices: {rig['lattices']}")
    rc, out, _ = run("info", mrfixit)
    check(rc == 0 and "rig" not in json.loads(out), "info without --rig has no rig key")

bcn = os.path.join(models, "X/BCN_Epileptic.X")
if os.path.exists(bcn):
    tested += 1
    rig = rig_of(bcn)
    if rig:
        check(limbs(rig) == [("arm", "left", "B_Clavicle_Left", "B_Hand_Left"),
                             ("arm", "right", "B_Clavicle_Right", "B_Hand_Right"),
                             ("leg", "left", "B_Hip_Left", "B_Ankle_Left"),
                             ("leg", "right", "B_Hip_Right", "B_Ankle_Right")], f"BCN limbs: {limbs(rig)}")

wuson = os.path.join(models, "X/Testwuson.X")
if os.path.exists(wuson):
    tested += 1
    rig = rig_of(wuson)
    if rig:
        check(rig["four_legged"], "Testwuson is four-legged")
        kinds = [l["kind"] for l in rig["limbs"]]
        check(kinds == ["front_leg"] * 2 + ["hind_leg"] * 2 + ["neck", "tail"], f"Testwuson limbs: {kinds}")
        check([c["name"] for c in rig["spring_chains"]] == ["tail"], f"Testwuson springs: {rig['spring_chains']}")
        check(rig["spring_chains"][0]["bones"][0] == "Tail01", f"Testwuson tail: {rig['spring_chains']}")

# Bad usage: a skeleton has no skin to choose from; a static model has no rig.
rc, _, err = run("info", os.path.join(os.path.dirname(__file__), "..", "data", "skeleton", "arm.sk"), "--rig")
check(rc == 2 and "--rig" in err, f"info S.sk --rig: exit {rc}: {err}")
box = os.path.join(models, "glTF2/BoxTextured-glTF/BoxTextured.gltf")
if os.path.exists(box):
    rc, _, err = run("info", box, "--rig")
    check(rc == 2 and "BoxTextured.gltf" in err and "no skin" in err, f"info static --rig: exit {rc}: {err}")

for f in failures:
    print("FAIL:", f)
print(f"info --rig ({tested} models):", "FAILED" if failures else "ok")
sys.exit(1 if failures else 0)
