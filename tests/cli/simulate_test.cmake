# `deform simulate` end to end: the reach-stretch-release-settle curve of the built-in character, a rig file naming
# its model, frame-rate independence, a clip with jiggling lattices, and exit 2 on bad usage and bad rigs.
# Run as: cmake -DDEFORM=<deform executable> -DWORK=<scratch folder> -P simulate_test.cmake
include(${CMAKE_CURRENT_LIST_DIR}/cli_test_common.cmake)

# Bad usage or input: exit 2, nothing on stdout, stderr mentions `text`.
function(expect_invalid text)
  expect_rejected("${text}" simulate ${ARGN})
endfunction()

# --- the built-in character reaches (1.2, 1.6, 0.3), far beyond its arm, holds until 2.5 s, lets go, settles ---
deform(simulate --builtin --target 1.2,1.6,0.3 --release-at 2.5 --seconds 5 --dt 0.05)
expect_equal("exit status" "${rc}" 0)
expect_between(0.05 0.05 dt)
string(JSON count LENGTH "${out}" samples)
expect_equal("sample count" "${count}" 101)
expect_between(0 0 samples 0 t)
expect_between(0 0 samples 0 stretch)
expect_between(4.99 5.01 samples 100 t)
# Reaching: the stretch overshoots (t = 0.3 s) ...
expect_between(0.7 0.9 samples 6 stretch)
# ... and has settled on the target by the release: within 1% of the 0.53 m stretch it took.
expect_between(1.195 1.205 samples 50 effector 0)
expect_between(1.595 1.605 samples 50 effector 1)
expect_between(0.295 0.305 samples 50 effector 2)
expect_between(0.5 0.56 samples 50 stretch)
# Released: it springs back past rest (a damped oscillation) and settles there.
set(lowest 1)
foreach(n RANGE 51 100)
  string(JSON s GET "${out}" samples ${n} stretch)
  if(s LESS lowest)
    set(lowest ${s})
  endif()
endforeach()
# ... but no lower than the length floor (default 70%): the two stretched lattices, 0.56 m together, shorten by at
# most 0.17 m.
if(NOT lowest LESS -0.1 OR lowest LESS -0.17)
  fail("the spring-back past rest after the release is not cut by the length floor: lowest stretch ${lowest}")
endif()
expect_between(-0.006 0.006 samples 100 stretch)

# --- frame-rate independence: the same curve at dt = 0.025 s agrees at t = 1 s within 0.01 m (2% of the stretch) ---
# A decimal number as an integer count of micrometres (CMake has only integer arithmetic).
function(to_micro value out_var)
  if(value MATCHES "[eE]")  # 1.2e-05 and the like: below a micrometre here
    set(${out_var} 0 PARENT_SCOPE)
    return()
  endif()
  string(REGEX MATCH "^(-?)([0-9]*)\\.?([0-9]*)$" matched "${value}")
  set(sign "${CMAKE_MATCH_1}")
  set(whole "${CMAKE_MATCH_2}")
  string(SUBSTRING "${CMAKE_MATCH_3}000000" 0 6 fraction)
  if(whole STREQUAL "")
    set(whole 0)
  endif()
  # The six fraction digits with a leading 1, less 10⁶: their value whatever zeros they start with. (A REGEX REPLACE
  # of "^0+" is applied again after each match, so it turned "030655" into "3655".)
  math(EXPR micro "${sign}(${whole} * 1000000 + 1${fraction} - 1000000)")
  set(${out_var} ${micro} PARENT_SCOPE)
endfunction()
string(JSON coarse GET "${out}" samples 20 stretch)
deform(simulate --builtin --target 1.2,1.6,0.3 --release-at 2.5 --seconds 1 --dt 0.025)
expect_equal("exit status" "${rc}" 0)
expect_between(0.99 1.01 samples 40 t)
string(JSON fine GET "${out}" samples 40 stretch)
to_micro("${coarse}" coarse_micro)
to_micro("${fine}" fine_micro)
math(EXPR difference "${fine_micro} - ${coarse_micro}")
if(difference GREATER 10000 OR difference LESS -10000)
  fail("stretch at t = 1 s: ${coarse} at dt 0.05, ${fine} at dt 0.025")
endif()

# The largest difference of two runs' stretch and effector at the samples they share (every `ratio`-th of the fine
# run), in micrometres, into `out_var`.
function(largest_difference coarse_json fine_json ratio out_var)
  string(JSON count LENGTH "${coarse_json}" samples)
  math(EXPR last "${count} - 1")
  set(largest 0)
  foreach(n RANGE 0 ${last})
    math(EXPR m "${n} * ${ratio}")
    foreach(path "effector;0" "effector;1" "effector;2" "stretch")
      string(JSON a GET "${coarse_json}" samples ${n} ${path})
      string(JSON b GET "${fine_json}" samples ${m} ${path})
      to_micro("${a}" a_micro)
      to_micro("${b}" b_micro)
      math(EXPR d "${a_micro} - ${b_micro}")
      if(d LESS 0)
        math(EXPR d "-${d}")
      endif()
      if(d GREATER largest)
        set(largest ${d})
      endif()
    endforeach()
  endforeach()
  set(${out_var} ${largest} PARENT_SCOPE)
endfunction()

# --- the release happens at T whatever the step: 30 Hz (1.0 / dt lands a rounding error away from a step) and 240 Hz
# agree within 10 micrometres (0.001% of the 0.82 m peak) at every 1/30 s, through the reach and the release ---
deform(simulate --builtin --target 1.2,1.6,0.3 --release-at 1.0 --seconds 3 --dt 0.0333333333)
expect_equal("exit status at 30 Hz" "${rc}" 0)
set(at_30 "${out}")
string(JSON count LENGTH "${at_30}" samples)
expect_equal("sample count at 30 Hz" "${count}" 91)
expect_between(0.999 1.001 samples 30 t)
deform(simulate --builtin --target 1.2,1.6,0.3 --release-at 1.0 --seconds 3 --dt 0.0041666666667)
expect_equal("exit status at 240 Hz" "${rc}" 0)
largest_difference("${at_30}" "${out}" 8 largest)
if(largest GREATER 10)
  fail("30 Hz and 240 Hz differ by ${largest} micrometres with a release at 1.0 s")
endif()
# A step of 0.3 s crosses T = 1 s (0.9 to 1.2): it is split there, so at 1.2 s and after it agrees with steps of 0.1.
deform(simulate --builtin --target 1.2,1.6,0.3 --release-at 1.0 --seconds 2.4 --dt 0.3)
expect_equal("exit status with steps of 0.3" "${rc}" 0)
set(at_03 "${out}")
deform(simulate --builtin --target 1.2,1.6,0.3 --release-at 1.0 --seconds 2.4 --dt 0.1)
largest_difference("${at_03}" "${out}" 3 largest)
if(largest GREATER 10)
  fail("steps of 0.3 s and 0.1 s differ by ${largest} micrometres with a release at 1.0 s")
endif()

# --- the length floor and volume compensation can be set: without the floor the arm swings much further back ---
deform(simulate --builtin --target 1.2,1.6,0.3 --release-at 2.5 --seconds 5 --dt 0.05 --min-length 0 --volume 0)
expect_equal("exit status without a floor" "${rc}" 0)
set(lowest 1)
foreach(n RANGE 51 100)
  string(JSON s GET "${out}" samples ${n} stretch)
  if(s LESS lowest)
    set(lowest ${s})
  endif()
endforeach()
if(NOT lowest LESS -0.2)
  fail("no deep spring-back without the length floor: lowest stretch ${lowest}")
endif()

# --- a rig file that names its model ---
file(WRITE "${WORK}/forearm.rig.json" [=[
{"rig": 1, "model": "builtin",
 "reach": {"effector": "hand_l", "root": "clavicle_l"},
 "lattices": [{"name": "upper", "bone": "upperarm_l"},
              {"name": "fore", "bone": "forearm_l", "elastic": {"stiffness": 400, "damping_ratio": 1}}]}
]=])
deform(simulate "${WORK}/forearm.rig.json" --target 1.2,1.6,0.3 --seconds 2 --dt 0.1)
expect_equal("exit status with a rig file" "${rc}" 0)
expect_between(1.19 1.21 samples 15 effector 0)

# --- a clip: the walk plays, the lattices with inertia lag behind it and jiggle; 15 Hz and 240 Hz agree within 6 mm
# (about 1% of the fingers' travel: a cubic between 15 Hz frames has the acceleration the lattices feel to O(h²)).
# The fingers, in the hand's lattice: the wrist itself stays on the forearm's bone (the arm's lattices keep their
# joints, LatticeMotion::far_share), the flesh and the hand's end jiggle ---
deform(simulate --builtin --clip walk --inertia 1 --seconds 2 --dt 0.0666666666667 --effector fingers1_l)
expect_equal("exit status of a clip at 15 Hz" "${rc}" 0)
set(walk_15 "${out}")
deform(simulate --builtin --clip walk --inertia 1 --seconds 2 --dt 0.0041666666667 --effector fingers1_l)
expect_equal("exit status of a clip at 240 Hz" "${rc}" 0)
largest_difference("${walk_15}" "${out}" 16 largest)
if(largest GREATER 6000)
  fail("the walk with inertia at 15 Hz and 240 Hz differs by ${largest} micrometres")
endif()
deform(simulate --builtin --clip walk --seconds 2 --dt 0.0666666666667 --effector fingers1_l)
largest_difference("${walk_15}" "${out}" 1 largest)
if(largest LESS 20000)
  fail("inertia 1 moves the walking fingers by only ${largest} micrometres off the rigid walk")
endif()
# A clip and a target: the hand reaches while the body walks.
deform(simulate --builtin --clip walk --target 1.2,1.6,0.3 --inertia 0.5 --release-at 1.5 --seconds 2 --dt 0.05)
expect_equal("exit status of a clip and a target" "${rc}" 0)
expect_between(1.14 1.26 samples 28 effector 0)
expect_between(1.54 1.66 samples 28 effector 1)

# --inertia is a scale of each lattice's tuned inertia, its part's: --inertia 1 is the rig with every lattice at its
# part's default_lattice_motion inertia (upper arm and forearm 0.3, hand 0.2: docs/elasticity.md), spelled out here
# in the rig the built-in character runs with, the same run to the last digit; and the saved rig says so.
deform(simulate --builtin --clip run --seconds 1 --dt 0.05 --save-rig "${WORK}/builtin.rig.json")
file(READ "${WORK}/builtin.rig.json" rig)
foreach(i 0 1 2)
  string(JSON part GET "${rig}" lattices ${i} motion part)
  if(part STREQUAL "hand")
    string(JSON rig SET "${rig}" lattices ${i} motion inertia 0.2)
  else()
    string(JSON rig SET "${rig}" lattices ${i} motion inertia 0.3)
  endif()
  list(APPEND parts "${part}")
endforeach()
expect_equal("the built-in rig's parts" "${parts}" "upper_limb;lower_limb;hand")
file(WRITE "${WORK}/tuned.rig.json" "${rig}")
deform(simulate "${WORK}/tuned.rig.json" --clip run --seconds 1 --dt 0.05)
expect_equal("exit status of the tuned rig" "${rc}" 0)
set(tuned "${out}")
deform(simulate --builtin --clip run --inertia 1 --seconds 1 --dt 0.05 --save-rig "${WORK}/scaled.rig.json")
if(NOT out STREQUAL tuned)
  fail("--inertia 1 is not the rig with each part's tuned inertia")
endif()
file(READ "${WORK}/scaled.rig.json" out)
expect_between(0.1999999 0.2000001 lattices 2 motion inertia)  # the hand's
deform(simulate --builtin --clip run --inertia 0.5 --seconds 1 --dt 0.05 --save-rig "${WORK}/scaled.rig.json")
file(READ "${WORK}/scaled.rig.json" out)
expect_between(0.1499999 0.1500001 lattices 0 motion inertia)  # the upper arm's: half its 0.3

# Every built-in clip plays; the effector (the left hand) moves with it.
foreach(name idle run wave)
  deform(simulate --builtin --clip ${name} --inertia 0.5 --seconds 1 --dt 0.1)
  expect_equal("exit status of the ${name} clip" "${rc}" 0)
  string(JSON count LENGTH "${out}" samples)
  expect_equal("sample count of the ${name} clip" "${count}" 11)
endforeach()
# A rig file on the built-in character has its clips too: the right arm's lattices (the full rig's right arm) wave
# while the right hand reaches out to the right, beyond its length.
file(WRITE "${WORK}/right-arm.rig.json" [=[
{"rig": 1, "model": "builtin",
 "reach": {"effector": "hand_r", "root": "clavicle_r"},
 "lattices": [{"name": "upperarm_r", "bone": "upperarm_r"},
              {"name": "forearm_r", "bone": "forearm_r"},
              {"name": "hand_r", "bone": "hand_r"}]}
]=])
deform(simulate "${WORK}/right-arm.rig.json" --clip wave --target -1.2,1.6,0.3 --release-at 3 --seconds 2 --dt 0.05)
expect_equal("exit status of a rig file on the built-in character with a clip" "${rc}" 0)
expect_between(-1.26 -1.14 samples 40 effector 0)
expect_between(1.54 1.66 samples 40 effector 1)
expect_between(0.2 1 samples 40 stretch)

# --- bad usage and bad input: exit 2 ---
expect_invalid("no clip named 'jump' (the model has 'idle', 'walk', 'run', 'wave')" --builtin --clip jump)
expect_invalid("--inertia" --builtin --clip walk --inertia 2)
expect_invalid("--target" --builtin)
expect_invalid("expected a model (MODEL, MESH.obj --skeleton S.sk --weights W.skw, or --builtin) or a RIG.json"
               --target 1,2,3)
expect_invalid("--builtin takes no model file" --builtin "${WORK}/forearm.rig.json" --target 1,2,3)
expect_invalid("--dt" --builtin --target 1,2,3 --dt 0)
expect_invalid("--dt" --builtin --target 1,2,3 --dt fast)
expect_invalid("--target" --builtin --target 1,2)
expect_invalid("--effector" --builtin --target 1,2,3 --effector tail)
expect_invalid("--integrator" --builtin --target 1,2,3 --integrator euler)
expect_invalid("--min-length" --builtin --target 1,2,3 --min-length 1)
expect_invalid("--min-length" --builtin --target 1,2,3 --min-length -0.1)
expect_invalid("--volume" --builtin --target 1,2,3 --volume 1.5)
expect_invalid("--volume" --builtin --target 1,2,3 --volume thin)
expect_invalid("missing.rig.json" "${WORK}/missing.rig.json" --target 1,2,3)
file(WRITE "${WORK}/bad.rig.json" [=[{"rig": 1, "model": "builtin", "lattices": [{"name": "a", "bone": "forearm_l", "degree": [3, 0, 3]}]}]=])
expect_invalid("lattices[0].degree[1]" "${WORK}/bad.rig.json" --target 1,2,3)
file(WRITE "${WORK}/no-effector.rig.json" [=[{"rig": 1, "model": "builtin", "lattices": []}]=])
expect_invalid("--effector" "${WORK}/no-effector.rig.json" --target 1,2,3)
# The seed's Verlet is only conditionally stable: a step beyond its bound is refused, not printed as a diverging curve.
expect_invalid("stable for --dt below 0.16" --builtin --target 1.3,1.6,0.4 --integrator verlet --dt 0.5 --seconds 5)

deform(simulate --help)
expect_equal("exit status of --help" "${rc}" 0)
string(FIND "${out}" "usage: deform simulate" found)
if(found EQUAL -1)
  fail("--help does not print the usage")
endif()
