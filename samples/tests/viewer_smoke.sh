#!/usr/bin/env bash
# Smoke test of the viewer under Xvfb with Mesa's software renderer: a frame before a reach and one after it,
# both non-blank, the character covering a plausible share of pixels, and the two different. Also one full
# (non-bare) screenshot; the built-in walk (--clip walk) alone, with a reach, in full with a spring chain and blended
# with the run (--blend run); one with a bone's weight map; a reach with a pole and one with swing-twist limits; the
# frame after the reach again with the deformation on the GPU (--gpu), LBS and DQS, which must be the same pictures
# (skipped without OpenGL 4.3); the up axis a Z-up FBX declares and an imported character on the floor of its clip
# (when Debian's assimp-testmodels are there), and a glTF model's morph targets, played by its clip and held; the
# lattice overlay drawing the reaching limb's lattices only, unless all are asked for; the bent elbow with Direct
# Delta Mush and with Delta Mush; the walk at a level of detail and at the four levels of --lod (chosen, and picked
# by the zoom), and mrfixit's; imported characters framed by the camera and standing on the floor, with and without
# their clip.
# usage: viewer_smoke.sh VIEWER PNG_CHECK WORKDIR [simplified|whole]  (the levels' meshes: the build has the simplify
# layer, or not; default whole)
set -euo pipefail
viewer=$1 check=$2 work=$3 level_meshes=${4:-whole}
mkdir -p "$work"
run() { xvfb-run -a -s "-screen 0 640x480x24" "$viewer" --width 640 --height 480 "$@"; }
run --bare --screenshot "$work/before.png" --frames 20
run --bare --screenshot "$work/after.png" --frames 40 --reach 1.3,1.6,0.4 --at 2
"$check" "$work/before.png" "$work/after.png"
full=$(run --screenshot "$work/full.png" --frames 30 --reach 1.3,1.6,0.4 --at 2 --release-at 20)
test -s "$work/full.png"
# Of the built-in character's 12 lattices the overlay draws the limb's that reached (upper arm, forearm, hand), not a
# cage over the whole body; all 12 on request (--lattices all, the panel's "all lattices", the L key).
all=$(run --screenshot "$work/all_lattices.png" --frames 1 --lattices all)
python3 - "$full" "$all" <<'PY'
import json, sys
full, every = json.loads(sys.argv[1]), json.loads(sys.argv[2])
assert full["lattices_shown"] == 3, full
assert every["lattices_shown"] == 12, every
PY
# A pole in front of the body lifts the elbow of a reach within the arm's length: another picture than without it;
# the same with swing-twist limits, their cones drawn.
run --bare --screenshot "$work/near.png" --frames 40 --reach 0.3,1.15,0.3 --at 2
run --bare --screenshot "$work/near_pole.png" --frames 40 --reach 0.3,1.15,0.3 --at 2 --pole 0.3,0.6,1.5
"$check" "$work/near.png" "$work/near_pole.png"
# The same bent elbow skinned by Direct Delta Mush (a rounder elbow) and with Delta Mush after LBS: other pictures
# than LBS's; both CPU stages, so --gpu with them deforms on the CPU.
run --bare --skinning ddm --screenshot "$work/near_ddm.png" --frames 40 --reach 0.3,1.15,0.3 --at 2 >/dev/null
"$check" "$work/near.png" "$work/near_ddm.png"
run --bare --mush 10 --screenshot "$work/near_mush.png" --frames 40 --reach 0.3,1.15,0.3 --at 2 >/dev/null
"$check" "$work/near.png" "$work/near_mush.png"
cpu=$(run --bare --skinning ddm --gpu --screenshot "$work/near_ddm_gpu.png" --frames 5 2>/dev/null)
grep -q '"gpu_lattices": false' <<<"$cpu" || { echo "$cpu"; exit 1; }
run --screenshot "$work/swing_twist.png" --frames 30 --reach 0.3,1.15,0.3 --at 2 --pole 0.3,0.6,1.5 \
  --limits swing-twist >/dev/null
test -s "$work/swing_twist.png"

# The built-in walk with the jiggle (lattices with inertia): another pose than the bind pose and another picture
# than the rigid walk (--inertia 0); with a reach while walking, another again (png_check's coverage bound also
# catches a flung, exploded arm); and in full, the rig's spring chain (right fingers) drawn and a reach held.
rig=$(cd "$(dirname "$0")/../data" && pwd)/walk.rig.json
run --bare --screenshot "$work/walk.png" --frames 40 --clip walk
"$check" "$work/before.png" "$work/walk.png"
run --bare --screenshot "$work/walk_rigid.png" --frames 40 --clip walk --inertia 0  # the jiggle shows
"$check" "$work/walk_rigid.png" "$work/walk.png"
# A level of detail (--lod-bones): with every bone, the rigid walk's picture; with 8, merged on the walk's motion, the
# knees no longer bend: another picture.
run --bare --screenshot "$work/walk_lod33.png" --frames 40 --clip walk --inertia 0 --lod-bones 33 2>/dev/null
"$check" --same-picture "$work/walk_rigid.png" "$work/walk_lod33.png"
run --bare --screenshot "$work/walk_lod8.png" --frames 40 --clip walk --inertia 0 --lod-bones 8 2>/dev/null
"$check" "$work/walk_rigid.png" "$work/walk_lod8.png"
# The four levels of detail (--lod): level 0 is the rigid walk's picture; level 3 (a third of the bones, a tenth of the
# triangles where the simplify layer is built, every 4th frame) another; --lod auto picks level 0 at the framing
# distance, 1 at twice it, 2 at 4 times and 3 at 8 times (the character a half, a quarter, an eighth of the window high).
run --bare --screenshot "$work/walk_level0.png" --frames 40 --clip walk --inertia 0 --lod 0 2>/dev/null >/dev/null
"$check" --same-picture "$work/walk_rigid.png" "$work/walk_level0.png"
level3=$(run --bare --screenshot "$work/walk_level3.png" --frames 40 --clip walk --inertia 0 --lod 3 2>/dev/null)
"$check" "$work/walk_rigid.png" "$work/walk_level3.png"
autos=()
for zoom in 1 2 4 8; do
  autos+=("$(run --bare --screenshot "$work/walk_auto$zoom.png" --frames 10 --clip walk --lod auto --zoom $zoom 2>/dev/null)")
done
python3 - "$level_meshes" "$level3" "${autos[@]}" <<'PY'
import json, sys
level3, autos = json.loads(sys.argv[2]), [json.loads(a) for a in sys.argv[3:]]
assert level3["lod_level"] == 3, level3
assert [a["lod_level"] for a in autos] == [0, 1, 2, 3], autos
drawn = [a["lod_triangles"] for a in autos]                           # what the renderer draws
if sys.argv[1] == "simplified":
    assert drawn == [5696, 2848, 1424, 594], drawn                    # 0.5, 0.25 and 0.1 of the whole mesh
else:
    assert drawn == [5696] * 4, drawn
assert level3["lod_triangles"] == drawn[3], level3
PY
run --bare --screenshot "$work/walk_reach.png" --frames 40 --clip walk --reach 1.3,1.6,0.4 --at 2
"$check" "$work/walk.png" "$work/walk_reach.png"
run --screenshot "$work/walk_full.png" --frames 40 --clip walk --rig "$rig" --reach 1.3,1.6,0.4 --at 2 >/dev/null
test -s "$work/walk_full.png"
# The walk blended half and half with the run (in step with the walk's phase): another picture than the walk.
run --bare --screenshot "$work/walk_run.png" --frames 40 --clip walk --blend run --blend-weight 0.5
"$check" "$work/walk.png" "$work/walk_run.png"

# The weight map of one bone (points coloured by its weights, over the full picture).
run --screenshot "$work/weight_map.png" --frames 5 --weight-map upperarm_l >/dev/null
test -s "$work/weight_map.png"

# The whole deformation on the GPU (skinning, lattices and their normals; the CPU only poses): the same pictures as
# the CPU's, LBS and DQS, for the reach and for the walk whose lattices jiggle while it reaches.
run --bare --gpu --screenshot "$work/after_gpu.png" --frames 40 --reach 1.3,1.6,0.4 --at 2 > "$work/gpu.json"
if grep -q '"gpu_lattices": true' "$work/gpu.json"; then
  "$check" --same-picture "$work/after.png" "$work/after_gpu.png"
  run --bare --dqs --screenshot "$work/after_dqs.png" --frames 40 --reach 1.3,1.6,0.4 --at 2 >/dev/null
  run --bare --dqs --gpu --screenshot "$work/after_dqs_gpu.png" --frames 40 --reach 1.3,1.6,0.4 --at 2 >/dev/null
  "$check" --same-picture "$work/after_dqs.png" "$work/after_dqs_gpu.png"
  run --bare --gpu --screenshot "$work/walk_reach_gpu.png" --frames 40 --clip walk --reach 1.3,1.6,0.4 --at 2 >/dev/null
  "$check" --same-picture "$work/walk_reach.png" "$work/walk_reach_gpu.png"
else
  echo "GPU lattices skipped: no OpenGL 4.3"
fi

fbx=/usr/share/assimp/models/FBX/embedded_ascii/box.FBX  # UpAxis 2 in its metadata
if [ -f "$fbx" ]; then
  declared=$(run "$fbx" --bare --frames 1 --screenshot "$work/box.png" 2>&1 || true)
  if grep -q "no importer" <<<"$declared"; then
    echo "up axis skipped: no importer in this build"
  else
    grep -q '"up": \[0, 0, 1\]' <<<"$declared" || { echo "$declared"; exit 1; }
    run "$fbx" --bare --frames 1 --screenshot "$work/box.png" --up y 2>/dev/null | grep -q '"up": \[0, 1, 0\]'
  fi
fi
# An imported character stands on the floor in its clip: mrfixit.iqm's idle crouches below its bind pose's feet, so
# the floor is the lowest height the clip reaches (sampled at load), not the bind pose's; the character drawn
# mid-clip never sinks below it.
iqm=/usr/share/assimp/models/IQM/mrfixit.iqm
if [ -f "$iqm" ] && ! grep -q "no importer" <<<"${declared:-}"; then
  rest=$(run "$iqm" --bare --frames 1 --screenshot "$work/mrfixit.png" 2>/dev/null)
  for frames in 10 40 70; do
    idle=$(run "$iqm" --bare --clip idle --inertia 0 --frames $frames --screenshot "$work/mrfixit_idle.png" 2>/dev/null)
    python3 - "$rest" "$idle" <<'PY'
import json, sys
rest, idle = json.loads(sys.argv[1]), json.loads(sys.argv[2])
assert abs(rest["floor"] - rest["lowest"]) < 1e-5, rest            # unposed: the floor under the bind pose's feet
assert idle["floor"] < rest["floor"] - 1e-3, (rest, idle)          # the clip's floor, lower than the bind pose's
assert idle["lowest"] >= idle["floor"] - 1e-5, idle                 # standing on it, never through it
PY
  done
  # Its levels of detail: level 3 another picture of the idle than level 0, on fewer triangles.
  whole=$(run "$iqm" --bare --clip idle --inertia 0 --frames 30 --lod 0 --screenshot "$work/mrfixit_level0.png" 2>/dev/null)
  far=$(run "$iqm" --bare --clip idle --inertia 0 --frames 30 --lod 3 --screenshot "$work/mrfixit_level3.png" 2>/dev/null)
  "$check" "$work/mrfixit_level0.png" "$work/mrfixit_level3.png"
  python3 - "$whole" "$far" "$level_meshes" <<'PY'
import json, sys
whole, far = json.loads(sys.argv[1]), json.loads(sys.argv[2])
assert (whole["lod_level"], far["lod_level"]) == (0, 3), (whole, far)
if sys.argv[3] == "simplified":
    assert far["lod_triangles"] < whole["lod_triangles"], (whole, far)
else:
    assert far["lod_triangles"] == whole["lod_triangles"], (whole, far)
PY
fi
# An imported model with morph targets morphs: AnimatedMorphCube's clip animates target0 (the summary's weights
# follow it), --morph holds weights over the clip, and each picture differs from the one before.
cube=/usr/share/assimp/models/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf
if [ -f "$cube" ] && ! grep -q "no importer" <<<"${declared:-}"; then
  rest=$(run "$cube" --bare --frames 1 --screenshot "$work/cube.png" 2>/dev/null)
  played=$(run "$cube" --bare --clip Square --frames 60 --screenshot "$work/cube_square.png" 2>/dev/null)
  held=$(run "$cube" --bare --clip Square --frames 60 --morph target0:1,target1:0.5 \
         --screenshot "$work/cube_held.png" 2>/dev/null)
  python3 - "$rest" "$played" "$held" <<'PY'
import json, sys
rest, played, held = (json.loads(a) for a in sys.argv[1:4])
assert rest["morph_weights"] == [0, 0], rest                                      # the defaults
assert played["morph_weights"][0] > 0.5 and played["morph_weights"][1] == 0, played  # the clip's, 1 s in
assert held["morph_weights"] == [1, 0.5], held                                    # held over the clip
PY
  for pair in "cube.png cube_square.png" "cube_square.png cube_held.png"; do
    set -- $pair
    if cmp -s "$work/$1" "$work/$2"; then echo "morph targets: $1 and $2 are the same picture"; exit 1; fi
  done
fi
# A rig's corrective (samples/data/elbow_pad.rig.json): its pose driver sets its weight every frame, live with the
# clip (off at the bind pose, on as the run bends the elbow), and --morph cannot hold it against the driver.
rig=$(cd "$(dirname "$0")/../data" && pwd)/elbow_pad.rig.json
rest=$(run --rig "$rig" --bare --inertia 0 --frames 1 --screenshot "$work/pad_rest.png")
early=$(run --rig "$rig" --bare --inertia 0 --clip run --frames 10 --screenshot "$work/pad_early.png")
late=$(run --rig "$rig" --bare --inertia 0 --clip run --frames 20 --morph elbow_pad:0 --screenshot "$work/pad_late.png")
python3 - "$rest" "$early" "$late" <<'PY'
import json, sys
rest, early, late = (json.loads(a.splitlines()[-1]) for a in sys.argv[1:4])
assert len(rest["morph_weights"]) == 1 and abs(rest["morph_weights"][0]) < 1e-4, rest  # the bind pose: off
assert early["morph_weights"][0] > 0.05 and late["morph_weights"][0] > 0.05, (early, late)  # driven by the run
assert abs(early["morph_weights"][0] - late["morph_weights"][0]) > 1e-3, (early, late)     # live, frame by frame
PY
# Imported characters framed and on the floor: the camera fits the bind pose's box, or with a clip the box of the
# clip's sampled poses (a character whose clip stands it elsewhere than its bind pose stays in frame). In a bare
# 320x240 frame the silhouette spans 35-95% of the height, is cut at neither the top nor the bottom, and its lowest
# pixels are at the floor's row under them (the viewer's "floor_row"). mrfixit is Z-up, the others Y-up; each without
# and with its first clip (rigid, --inertia 0), at a moment a foot is down (the floor is the lowest the clip reaches).
small() { xvfb-run -a -s "-screen 0 320x240x24" "$viewer" --width 320 --height 240 --bare "$@"; }
models=/usr/share/assimp/models
if ! grep -q "no importer" <<<"${declared:-}"; then
  for entry in IQM/mrfixit.iqm:30 X/BCN_Epileptic.X:15 X/Testwuson.X:10 glTF2/simple_skin/simple_skin.gltf:30; do
    file=$models/${entry%:*} frames=${entry##*:}
    if [ ! -f "$file" ]; then echo "framing: $file missing, skipped"; continue; fi
    name=$(basename "${file%.*}")
    for clip in "" "#0"; do
      shot=$work/framed_$name${clip:+_clip}.png
      summary=$(small "$file" --frames "$frames" ${clip:+--clip "$clip" --inertia 0} --screenshot "$shot" 2>/dev/null)
      row=$(python3 -c 'import json, sys; print(json.loads(sys.argv[1])["floor_row"])' "$summary")
      "$check" --bbox "$shot" --floor-row "$row"
    done
  done
fi
# A figure whose bind pose lies on its back and whose clip stands it up, as the Khronos CesiumMan does (generated:
# lying_figure.py): lying, it fills the width; standing in its clip, the camera fitted to the bind pose would cut
# its top off, the one fitted to the clip frames it whole, on the floor.
python3 "$(dirname "$0")/lying_figure.py" "$work/lying_figure.gltf"
lying=$(small "$work/lying_figure.gltf" --frames 2 --screenshot "$work/framed_lying.png" 2>&1 || true)
if grep -q "no importer" <<<"$lying"; then
  echo "lying figure skipped: no importer in this build"
else
  row=$(python3 -c 'import json, sys; print(json.loads(sys.argv[1].splitlines()[-1])["floor_row"])' "$lying")
  "$check" --bbox "$work/framed_lying.png" --height 0.1,0.95 --width 0.35,0.95 --floor-row "$row"
  summary=$(small "$work/lying_figure.gltf" --frames 30 --clip stand --inertia 0 \
            --screenshot "$work/framed_standing.png")
  row=$(python3 -c 'import json, sys; print(json.loads(sys.argv[1])["floor_row"])' "$summary")
  "$check" --bbox "$work/framed_standing.png" --floor-row "$row"
fi
echo "viewer smoke test passed"
