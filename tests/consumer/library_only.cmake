# Building the libraries alone builds nothing else: configures libdeform (1) with DEFORM_LIBRARY_ONLY=ON and (2) as a
# subproject of another project, and fails if a test, benchmark, sample or tool target is there. Configure only.
file(REMOVE_RECURSE ${WORK_DIR})

function(check_targets build what)
  execute_process(COMMAND ${CMAKE_COMMAND} --build ${build} --target help OUTPUT_VARIABLE targets RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "${what}: listing the targets failed (${rc})")
  endif()
  foreach(wanted deform_runtime deform_offline deform_io deform_character deform_extras)
    if(NOT targets MATCHES "${wanted}")
      message(FATAL_ERROR "${what}: the library ${wanted} is missing")
    endif()
  endforeach()
  foreach(unwanted test_skinning deform_bench deform_viewer deform_cli deform_python)
    if(targets MATCHES "${unwanted}")
      message(FATAL_ERROR "${what}: ${unwanted} is configured although only the libraries were asked for")
    endif()
  endforeach()
  message(STATUS "${what}: only the libraries")
endfunction()

execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/library-only -G ${GENERATOR}
  -DDEFORM_LIBRARY_ONLY=ON OUTPUT_QUIET RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "configuring with DEFORM_LIBRARY_ONLY=ON failed (${rc})")
endif()
check_targets(${WORK_DIR}/library-only "DEFORM_LIBRARY_ONLY=ON")

execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer/subproject -B ${WORK_DIR}/subproject
  -G ${GENERATOR} -DLIBDEFORM_SOURCE=${SOURCE_DIR} OUTPUT_QUIET RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "configuring libdeform as a subproject failed (${rc})")
endif()
check_targets(${WORK_DIR}/subproject "add_subdirectory")
