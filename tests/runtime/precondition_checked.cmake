# Runs PROGRAM (tests/runtime/precondition_checked.cpp) and passes when it stopped with libstdc++'s assertion on an
# out-of-range operator[]: the sanitizer build checks the read accessors' index preconditions. ctest itself counts a
# program killed by abort() as failed whatever its output, hence this script between them.
execute_process(COMMAND "${PROGRAM}" RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(result EQUAL 0)
  message(FATAL_ERROR "the out-of-range accessor was not stopped (output: ${out})")
endif()
if(NOT err MATCHES "__n < this->size\\(\\)")
  message(FATAL_ERROR "stopped (${result}), but not by libstdc++'s index assertion: ${err}")
endif()
message(STATUS "stopped by the index assertion, as expected")
