# What the CLI tests share (each runs as `cmake -DDEFORM=<deform> -DWORK=<scratch folder> ... -P SCRIPT`):
# a fresh WORK folder, a way to run `deform`, and the assertions. A failed assertion is reported and the script goes
# on, so one run lists every failure; cmake exits non-zero at the end.
cmake_minimum_required(VERSION 3.25)
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")

function(fail message)
  message(SEND_ERROR "FAIL: ${message}")
endfunction()

# Runs `deform ARGS...`; sets rc (exit status), out (stdout) and err (stderr) in the caller.
function(deform)
  execute_process(COMMAND "${DEFORM}" ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
  set(rc "${code}" PARENT_SCOPE)
  set(out "${stdout}" PARENT_SCOPE)
  set(err "${stderr}" PARENT_SCOPE)
endfunction()

function(expect_equal what actual expected)
  if(NOT "${actual}" STREQUAL "${expected}")
    fail("${what}: got '${actual}', expected '${expected}'")
  endif()
endfunction()

# The JSON value at PATH... of `out` equals EXPECTED.
function(expect_json expected)
  string(JSON value GET "${out}" ${ARGN})
  expect_equal("${ARGN}" "${value}" "${expected}")
endfunction()

# The JSON number at PATH... of `out` lies within [LO, HI].
function(expect_between lo hi)
  string(JSON value GET "${out}" ${ARGN})
  if(NOT (value GREATER_EQUAL lo AND value LESS_EQUAL hi))
    fail("${ARGN}: ${value} not in [${lo}, ${hi}]")
  endif()
endfunction()

# The last run's stderr mentions TEXT.
function(expect_mentions text)
  string(FIND "${err}" "${text}" found)
  if(found EQUAL -1)
    fail("stderr '${err}' does not mention '${text}'")
  endif()
endfunction()

# Bad usage or invalid input: `deform ARGS...` exits 2, prints nothing on stdout, and its stderr mentions TEXT.
function(expect_rejected text)
  deform(${ARGN})
  expect_equal("exit status of ${ARGN}" "${rc}" 2)
  expect_equal("stdout of ${ARGN}" "${out}" "")
  string(FIND "${err}" "${text}" found)
  if(found EQUAL -1)
    fail("${ARGN}: stderr '${err}' does not mention '${text}'")
  endif()
endfunction()
