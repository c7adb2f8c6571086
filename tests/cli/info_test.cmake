# `deform info` end to end: the spec's JSON for a .sk and a mesh, and exit 2 with file and offset/line on bad input.
# Run as: cmake -DDEFORM=<deform executable> -DDATA=<tests/data> -DWORK=<scratch folder> -P info_test.cmake
include(${CMAKE_CURRENT_LIST_DIR}/cli_test_common.cmake)

# Invalid input: exit 2, a message naming the file and the given location text.
function(expect_invalid location)
  expect_rejected("${location}" info ${ARGN})
endfunction()

# --- a skeleton: tests/data/skeleton/arm.sk (written by test_skeleton_formats from skeleton_test_util.hpp) ---
deform(info "${DATA}/skeleton/arm.sk")
expect_equal("exit status, info arm.sk" "${rc}" 0)
string(JSON kind GET "${out}" kind)
expect_equal("kind" "${kind}" skeleton)
string(JSON bone_count LENGTH "${out}" bones)
expect_equal("bone count" "${bone_count}" 5)
string(REGEX MATCH "^{\n  \"kind\": \"skeleton\",\n  \"bones\": \\[" spec_order "${out}")
if(NOT spec_order)
  fail("keys not in the spec's order: ${out}")
endif()
expect_json(0 bones 0 id)
expect_json(root bones 0 name)
expect_json(-1 bones 0 parent)
expect_json(elbow bones 2 name)
expect_json(1 bones 2 parent)
expect_json(4 bones 4 id)
# Heads, hand-computed: root (0,1,0); shoulder +(0.5,0.5,0); elbow + Rz(-90)·(0,1,0) = (1.5,1.5,0);
# wrist + Rz(-90)·Rx(10)·Rz(20)·(0,0.8,0) = (2.24033, 1.77362, 0.13054); head (0,1.7,0.1).
expect_between(-1e-6 1e-6 bones 0 head 0)
expect_between(0.999999 1.000001 bones 0 head 1)
expect_between(0.499999 0.500001 bones 1 head 0)
expect_between(1.499999 1.500001 bones 1 head 1)
expect_between(1.499999 1.500001 bones 2 head 0)
expect_between(1.499999 1.500001 bones 2 head 1)
expect_between(-1e-6 1e-6 bones 2 head 2)
expect_between(2.24028 2.24038 bones 3 head 0)
expect_between(1.77357 1.77367 bones 3 head 1)
expect_between(0.13049 0.13059 bones 3 head 2)
expect_between(1.699999 1.700001 bones 4 head 1)
expect_between(0.099999 0.100001 bones 4 head 2)
expect_json(-10.0 bones 2 limits min 0)
expect_json(150.0 bones 2 limits max 2)
expect_json(0.0 bones 2 limits max 1)
expect_json(-180.0 bones 0 limits min 1)
expect_json(180.0 bones 0 limits max 2)

# --- a mesh: a cube of 8 points and 6 quads in two materials, with an MTL ---
file(WRITE "${WORK}/cube.mtl" "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n")
file(WRITE "${WORK}/cube.obj" "mtllib cube.mtl\no cube\n"
  "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 2\nv 1 0 2\nv 1 1 2\nv 0 1 2\n"
  "usemtl red\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\n"
  "usemtl blue\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n")
deform(info "${WORK}/cube.obj")
expect_equal("exit status, info cube.obj" "${rc}" 0)
expect_json(mesh kind)
expect_json(8 vertices)
expect_json(12 triangles)
expect_json(red materials 0)
expect_json(blue materials 1)
expect_json(6 faces)
expect_json(OFF has_uvs)
expect_json(2.0 bounds max 2)
expect_json(0.0 bounds min 0)

# --- usage and help ---
deform(info)
expect_equal("exit status, info without a file" "${rc}" 2)
deform(info a.sk b.sk)
expect_equal("exit status, info with two files" "${rc}" 2)
deform(info --bogus "${DATA}/skeleton/arm.sk")
expect_equal("exit status, info --bogus" "${rc}" 2)
deform(info --help)
expect_equal("exit status, info --help" "${rc}" 0)
string(FIND "${out}" "usage: deform info PATH" found)
if(found EQUAL -1)
  fail("info --help prints no usage: ${out}")
endif()

# --- invalid input: exit 2 naming file and byte offset / line ---
file(WRITE "${WORK}/bad_magic.sk" "SKEXzzzz")
expect_invalid("bad_magic.sk: byte 0" "${WORK}/bad_magic.sk")
file(WRITE "${WORK}/short.sk" "SKE")
expect_invalid("short.sk: byte 0" "${WORK}/short.sk")
file(WRITE "${WORK}/huge_count.sk" "SKELzzzz")  # bone count 0x7A7A7A7A
expect_invalid("huge_count.sk: byte 4" "${WORK}/huge_count.sk")
file(WRITE "${WORK}/broken.obj" "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n")
expect_invalid("broken.obj: line 4" "${WORK}/broken.obj")
expect_invalid("missing.sk" "${WORK}/missing.sk")
file(WRITE "${WORK}/notes.txt" "hello\n")
expect_invalid("notes.txt" "${WORK}/notes.txt")
