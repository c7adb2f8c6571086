# `deform ffd` end to end: hand-computed trilinear values, the vertex list, untouched vertices and faces, the JSON
# summary, exit 2 naming the key on bad lattices, and no output written on failure.
# Run as: cmake -DDEFORM=<deform executable> -DWORK=<scratch folder> -P ffd_test.cmake
include(${CMAKE_CURRENT_LIST_DIR}/cli_test_common.cmake)

# The `v` lines of an OBJ file, as a list of "x y z" strings; and the number of `f` lines.
function(read_obj path)
  file(STRINGS "${path}" lines)
  set(vs "")
  set(faces 0)
  foreach(line IN LISTS lines)
    if(line MATCHES "^v ([^ ]+) ([^ ]+) ([^ ]+)$")
      list(APPEND vs "${CMAKE_MATCH_1} ${CMAKE_MATCH_2} ${CMAKE_MATCH_3}")
    elseif(line MATCHES "^f ")
      math(EXPR faces "${faces} + 1")
    endif()
  endforeach()
  set(vs "${vs}" PARENT_SCOPE)
  set(faces "${faces}" PARENT_SCOPE)
endfunction()

# A 2×2×2 box at the origin; vertex 4 is outside it.
file(WRITE "${WORK}/box.obj" "v 1 1 1\nv 2 2 2\nv 0 0 0\nv 2 1 1\nv 3 3 3\nv 1 0.5 2\nf 1 2 3\nf 3 4 5 6\n")

# Degree 1, the far corner moved by +1 in x: trilinear weights u·v·w.
file(WRITE "${WORK}/corner.json"
  [[{"origin": [0, 0, 0], "size": [2, 2, 2], "degree": [1, 1, 1],
     "displacements": [{"index": [1, 1, 1], "offset": [1, 0, 0]}]}]])
deform(ffd "${WORK}/box.obj" --lattice "${WORK}/corner.json" --out "${WORK}/corner.obj")
expect_equal("corner exit code" "${rc}" "0")
expect_json(6 vertices)
expect_json(5 deformed)
expect_json(1 lattice degree 0)
expect_json(8 lattice control_points)
expect_json(1 lattice displacements)
expect_json("${WORK}/corner.obj" output)
read_obj("${WORK}/corner.obj")
# (1,1,1): 1/8 of the offset; (2,2,2): all of it; (0,0,0): none; (2,1,1): 1/4; (3,3,3): outside; (1,0.5,2): 1/8.
expect_equal("corner positions" "${vs}" "1.125 1 1;3 2 2;0 0 0;2.25 1 1;3 3 3;1.125 0.5 2")
expect_equal("corner faces" "${faces}" "2")

# The same lattice restricted to vertices 0 and 4 (0-based): only vertex 0 moves (4 is outside the box).
file(WRITE "${WORK}/listed.json"
  [[{"origin": [0, 0, 0], "size": [2, 2, 2], "degree": [1, 1, 1],
     "displacements": [{"index": [1, 1, 1], "offset": [1, 0, 0]}], "vertices": [0, 4]}]])
deform(ffd "${WORK}/box.obj" --lattice "${WORK}/listed.json" --out "${WORK}/listed.obj")
expect_equal("listed exit code" "${rc}" "0")
expect_json(1 deformed)
expect_json(2 lattice vertices)
read_obj("${WORK}/listed.obj")
expect_equal("listed positions" "${vs}" "1.125 1 1;2 2 2;0 0 0;2 1 1;3 3 3;1 0.5 2")

# Tricubic default: the centre moves by (3/8)³ = 27/512 of an interior point's offset (512 → 27).
file(WRITE "${WORK}/cubic.json"
  [[{"origin": [0, 0, 0], "size": [2, 2, 2], "displacements": [{"index": [1, 1, 1], "offset": [0, 0, 512]}]}]])
deform(ffd "${WORK}/box.obj" --lattice "${WORK}/cubic.json" --out "${WORK}/cubic.obj")
expect_equal("cubic exit code" "${rc}" "0")
expect_json(3 lattice degree 2)
read_obj("${WORK}/cubic.obj")
list(GET vs 0 centre)
string(REPLACE " " ";" centre "${centre}")
# Rest points at thirds of the size are not exact in binary: accept N, N.00000… or (N−1).99999….
function(expect_about what value integer)
  math(EXPR below "${integer} - 1")
  if(NOT (value MATCHES "^${integer}$" OR value MATCHES "^${integer}\\.00000[0-9]*$" OR
          value MATCHES "^${below}\\.99999[0-9]*$"))
    fail("${what}: got '${value}', expected about ${integer}")
  endif()
endfunction()
list(GET centre 0 x)
list(GET centre 1 y)
list(GET centre 2 z)
expect_about("cubic centre x" "${x}" 1)
expect_about("cubic centre y" "${y}" 1)
expect_about("cubic centre z" "${z}" 28)

# Invalid lattices: exit 2, the message names the file and the key; an existing output is left alone.
file(WRITE "${WORK}/keep.obj" "untouched\n")
function(expect_invalid json key)
  file(WRITE "${WORK}/bad.json" "${json}")
  deform(ffd "${WORK}/box.obj" --lattice "${WORK}/bad.json" --out "${WORK}/keep.obj")
  expect_equal("exit code for ${key}" "${rc}" "2")
  string(FIND "${err}" "bad.json" has_file)
  string(FIND "${err}" "${key}" has_key)
  if(has_file EQUAL -1 OR has_key EQUAL -1)
    fail("message for ${key} does not name the file and key: ${err}")
  endif()
  file(READ "${WORK}/keep.obj" kept)
  expect_equal("output after a failure (${key})" "${kept}" "untouched\n")
endfunction()
expect_invalid([[{"origin": [0, 0, 0], "size": [2, 2, 2], "degree": [1, 1, 1], "displacements": [
  {"index": [0, 0, 0], "offset": [1, 0, 0]}, {"index": [1, 0, 0], "offset": [1, 0, 0]},
  {"index": [2, 0, 0], "offset": [1, 0, 0]}]}]] "displacements[2].index")
expect_invalid([[{"origin": [0, 0, 0], "size": [2, 0, 2]}]] "size[1]")
expect_invalid([[{"origin": [0, 0, 0], "size": [2, -1, 2]}]] "size[1]")
expect_invalid([[{"origin": [0, 0, 0], "size": [2, 2, 2], "degree": [0, 3, 3]}]] "degree[0]")
expect_invalid([[{"origin": [0, 0, 1e999], "size": [2, 2, 2]}]] "bad.json")
expect_invalid([[{"origin": [0, 0, 0], "size": [2, 2, 2], "vertices": [0, 6]}]] "vertices[1]")
expect_invalid([[{"origin": [0, 0, 0], "size": [2, 2, 2], "displacements": [{"index": [0, 0, 0],
  "offset": [0, "x", 0]}]}]] "displacements[0].offset[1]")
expect_invalid([=[{"origin": [0, 0, 0], "size": [2, 2, 2]]=] "byte")

# Bad usage: exit 2.
deform(ffd "${WORK}/box.obj" --out "${WORK}/keep.obj")
expect_equal("missing --lattice" "${rc}" "2")
deform(ffd "${WORK}/missing.obj" --lattice "${WORK}/corner.json" --out "${WORK}/keep.obj")
expect_equal("missing mesh" "${rc}" "2")
deform(ffd --help)
expect_equal("--help" "${rc}" "0")
