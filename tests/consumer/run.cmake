# Installs the already-built libdeform into a scratch prefix, then configures, builds and runs a tiny consumer
# project against it with find_package(libdeform CONFIG): what an engine integrating the SDK does. Twice: once
# without components (Assimp must not be looked for, deform::gpu not defined), once with the components the build
# has (import, gpu).
file(REMOVE_RECURSE ${WORK_DIR})
if(NOT BUILD_TYPE)
  set(BUILD_TYPE Release)
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${WORK_DIR}/prefix --config ${BUILD_TYPE}
  RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "install failed (${rc})")
endif()

function(consume name with_import with_gpu)
  set(build ${WORK_DIR}/${name})
  execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer -B ${build} -G ${GENERATOR}
    -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DWITH_IMPORT=${with_import}
    -DWITH_GPU=${with_gpu}
    RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "configuring the consumer (${name}) failed (${rc})")
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} --build ${build} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "building the consumer (${name}) failed (${rc})")
  endif()
  set(programs runtime_only facade)
  if(with_import)
    list(APPEND programs importer)
  endif()
  if(with_gpu)
    list(APPEND programs gpu)
  endif()
  foreach(program ${programs})
    execute_process(COMMAND ${build}/${program} RESULT_VARIABLE rc OUTPUT_VARIABLE out)
    message(STATUS "${out}")
    if(rc)
      message(FATAL_ERROR "the consumer's ${program} failed (${rc})")
    endif()
  endforeach()
endfunction()

if(NOT HAVE_GPU)
  set(HAVE_GPU OFF)
endif()
consume(plain OFF OFF)
if(HAVE_IMPORT OR HAVE_GPU)
  consume(with-components ${HAVE_IMPORT} ${HAVE_GPU})
endif()

# --- the C API from C alone (docs/c-api.md's frame loop): a project(x C) with find_package, then a plain compiler
# line with pkg-config (deform-c.pc) ---
file(READ ${SOURCE_DIR}/docs/c-api.md c_api_page)
string(REGEX MATCH "```c\n([^`]*)```" c_api_example "${c_api_page}")
if(NOT CMAKE_MATCH_1)
  message(FATAL_ERROR "docs/c-api.md: no ```c example found")
endif()
file(WRITE ${WORK_DIR}/frame_loop.c "${CMAKE_MATCH_1}")
function(run_frame_loop program what)
  execute_process(COMMAND ${program} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc OR NOT out MATCHES "stretch at the end: ")
    message(FATAL_ERROR "${what}: the frame loop failed (${rc}): ${out}${err}")
  endif()
  message(STATUS "${what}: ${out}")
endfunction()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer/c_only -B ${WORK_DIR}/c-only -G ${GENERATOR}
  -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DEXAMPLE=${WORK_DIR}/frame_loop.c
  RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "configuring the C-only consumer failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/c-only RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "building the C-only consumer (project(x C), deform::c) failed (${rc})")
endif()
run_frame_loop(${WORK_DIR}/c-only/frame_loop "project(x C) with deform::c")

find_program(PKG_CONFIG pkg-config)
find_program(CC NAMES cc gcc clang)
if(PKG_CONFIG AND CC)
  file(GLOB pc_file ${WORK_DIR}/prefix/lib*/pkgconfig/deform-c.pc ${WORK_DIR}/prefix/lib/*/pkgconfig/deform-c.pc)
  if(NOT pc_file)
    message(FATAL_ERROR "no deform-c.pc was installed under ${WORK_DIR}/prefix")
  endif()
  get_filename_component(pc_dir "${pc_file}" DIRECTORY)
  # cc frame_loop.c $(pkg-config --cflags --libs deform-c): the line docs/c-api.md gives, through a shell.
  execute_process(COMMAND sh -c "${CC} -std=c11 ${WORK_DIR}/frame_loop.c -o ${WORK_DIR}/frame_loop_pc \
$(PKG_CONFIG_PATH=${pc_dir} ${PKG_CONFIG} --cflags --libs deform-c)"
    RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "cc ... $(pkg-config --cflags --libs deform-c) failed (${rc}): ${err}")
  endif()
  run_frame_loop(${WORK_DIR}/frame_loop_pc "cc with pkg-config")
else()
  message(STATUS "no pkg-config or C compiler: the pkg-config build is not tried")
endif()
