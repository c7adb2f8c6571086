# `deform weights` end to end: the built-in character and its files give the same .skw as samples/data holds, the
# options act, bad usage and bad input exit 2 without touching the output.
# Run as: cmake -DDEFORM=<deform executable> -DSAMPLES=<samples/data> -DWORK=<scratch folder> -P weights_test.cmake
include(${CMAKE_CURRENT_LIST_DIR}/cli_test_common.cmake)

# Runs `deform weights ARGS...`; sets rc, out, err in the caller.
function(weights)
  deform(weights ${ARGN})
  set(rc "${rc}" PARENT_SCOPE)
  set(out "${out}" PARENT_SCOPE)
  set(err "${err}" PARENT_SCOPE)
endfunction()

# Bad usage or input: exit 2, nothing on stdout, stderr mentions `text`.
function(expect_invalid text)
  expect_rejected("${text}" weights ${ARGN})
endfunction()

# --- the built-in character ---
weights(--builtin --out "${WORK}/builtin.skw")
expect_equal("exit status, --builtin" "${rc}" 0)
expect_json(builtin mesh)
expect_json(2554 vertices)
expect_json(29 bones)
expect_json(4 max_influences)
expect_json("${WORK}/builtin.skw" output)
file(STRINGS "${WORK}/builtin.skw" lines LIMIT_COUNT 3)
list(GET lines 0 header)
list(GET lines 1 count)
expect_equal("skw header" "${header}" "skw 1")
expect_equal("skw count" "${count}" "vertices 2554")
# The same weights as the file samples/data holds (written by make_builtin; test_builtin compares them to within a
# rounding on any platform, here they are the same bytes).
file(SHA256 "${WORK}/builtin.skw" built)
file(SHA256 "${SAMPLES}/builtin.skw" shipped)
expect_equal("--builtin .skw = samples/data/builtin.skw" "${built}" "${shipped}")

# --- the same character from its OBJ and .sk files ---
weights("${SAMPLES}/builtin.obj" --skeleton "${SAMPLES}/builtin.sk" --out "${WORK}/files.skw")
expect_equal("exit status, OBJ + .sk" "${rc}" 0)
expect_json("${SAMPLES}/builtin.obj" mesh)
expect_json(2554 vertices)
file(SHA256 "${WORK}/files.skw" from_files)
expect_equal("OBJ + .sk gives the built-in weights" "${from_files}" "${built}")

# --- options act ---
weights(--builtin --max-influences 1 --smoothing 0 --out "${WORK}/one.skw")
expect_equal("exit status, --max-influences 1" "${rc}" 0)
expect_json(1 max_influences)
file(STRINGS "${WORK}/one.skw" lines)
list(LENGTH lines line_count)
expect_equal("lines of one.skw" "${line_count}" 2556)
foreach(line IN LISTS lines)
  if(NOT line MATCHES "^(skw 1|vertices 2554|[0-9]+ [0-9]+ 1)$")
    fail("one.skw: '${line}' is not one bone with weight 1")
    break()
  endif()
endforeach()
weights(--builtin --falloff 1 --out "${WORK}/soft.skw")
expect_equal("exit status, --falloff 1" "${rc}" 0)
file(SHA256 "${WORK}/soft.skw" soft)
if(soft STREQUAL built)
  fail("--falloff 1 changed nothing")
endif()

# --- bad usage and bad input: exit 2, the output untouched ---
file(WRITE "${WORK}/keep.skw" "keep")
expect_invalid("--out is required" --builtin)
expect_invalid("--max-influences" --builtin --max-influences 5 --out "${WORK}/keep.skw")
expect_invalid("--falloff" --builtin --falloff 0 --out "${WORK}/keep.skw")
expect_invalid("--falloff" --builtin --falloff abc --out "${WORK}/keep.skw")
expect_invalid("--smoothing" --builtin --smoothing -1 --out "${WORK}/keep.skw")
expect_invalid("--builtin takes no MESH" --builtin "${SAMPLES}/builtin.obj" --out "${WORK}/keep.skw")
expect_invalid("--skeleton is required" "${SAMPLES}/builtin.obj" --out "${WORK}/keep.skw")
expect_invalid("missing.obj" "${WORK}/missing.obj" --skeleton "${SAMPLES}/builtin.sk" --out "${WORK}/keep.skw")
file(WRITE "${WORK}/bad.sk" "SKELxyz")
expect_invalid("bad.sk: byte" "${SAMPLES}/builtin.obj" --skeleton "${WORK}/bad.sk" --out "${WORK}/keep.skw")
expect_invalid("unknown option" --builtin --weights x.skw --out "${WORK}/keep.skw")
file(READ "${WORK}/keep.skw" kept)
expect_equal("output after failed runs" "${kept}" "keep")
