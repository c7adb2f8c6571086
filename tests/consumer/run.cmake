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
