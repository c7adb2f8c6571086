# The engine's build on x86-64 Linux (tests/engine/CMakeLists.txt), against this build of libdeform: the
# engine_scene_native test. It
#  1. installs the built libraries into WORK_DIR/libdeform and makes the engine's own prefix of header-only packages
#     in WORK_DIR/prefix (cmake/toolchains/header_prefix.cmake, copies: not links to /usr/include);
#  2. configures the engine with its native toolchain file (cmake/toolchains/x86_64-linux-gnu.cmake: packages only
#     from its prefixes) taking libdeform with find_package, builds it and runs its tests: the scene, which writes
#     WORK_DIR/package/scene.txt (the reference the cross passes compare with), and the check that every GLM header
#     it read came from the prefix;
#  3. configures it again taking libdeform with add_subdirectory (configure only: building the libraries a second
#     time is the cross passes' job), which fails unless libdeform took GLM and nlohmann-json from the prefix.
file(REMOVE_RECURSE ${WORK_DIR})
set(toolchain ${SOURCE_DIR}/cmake/toolchains/x86_64-linux-gnu.cmake)

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}${err}")
  endif()
  message(STATUS "${what}: done")
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

run("installing libdeform"
    ${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${WORK_DIR}/libdeform --config ${BUILD_TYPE})
run("making the engine's prefix" ${CMAKE_COMMAND} -DPREFIX=${WORK_DIR}/prefix -DCOPY=ON
    -P ${SOURCE_DIR}/cmake/toolchains/header_prefix.cmake)

run("configuring the engine (find_package)" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/engine -B ${WORK_DIR}/package
    -G ${GENERATOR} --toolchain ${toolchain} -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DENGINE_LIBDEFORM=package
    "-DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix\;${WORK_DIR}/libdeform")
run("building the engine (find_package)" ${CMAKE_COMMAND} --build ${WORK_DIR}/package)
run("the engine's tests (find_package)" ${CMAKE_CTEST_COMMAND} --test-dir ${WORK_DIR}/package --output-on-failure -V)
message(STATUS "${run_output}")

run("configuring the engine (add_subdirectory)" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/engine
    -B ${WORK_DIR}/subdirectory -G ${GENERATOR} --toolchain ${toolchain} -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
    -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix)
