# deform::runtime is the per-frame layer: it must not hold file streams, iostreams or JSON (docs/architecture.md).
# Reads every symbol of the built library, defined or referenced, and fails naming the first offenders. OTHER is a
# library that does use file streams, read the same way, so that the test fails if the pattern stops matching.
set(forbidden "basic_[io]?fstream|basic_filebuf|basic_[io]?stringstream|basic_iostream|basic_istream|basic_ostream|ios_base::Init|std::cout|std::cerr|std::clog|nlohmann|\\bfopen\\b|\\bfwrite\\b|\\bfread\\b")

function(offenders library out)
  execute_process(COMMAND ${NM} -C ${library} OUTPUT_VARIABLE symbols ERROR_QUIET RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "nm failed on ${library} (${rc})")
  endif()
  string(REGEX MATCHALL "[^\n]*(${forbidden})[^\n]*" found "${symbols}")
  set(${out} "${found}" PARENT_SCOPE)
endfunction()

offenders(${OTHER} control)
if(NOT control)
  message(FATAL_ERROR "the pattern finds no file stream in ${OTHER}, which has them: the test would prove nothing")
endif()
offenders(${LIBRARY} found)
if(found)
  list(LENGTH found count)
  list(SUBLIST found 0 10 first)
  list(JOIN first "\n" text)
  message(FATAL_ERROR "${LIBRARY} holds ${count} file, iostream or JSON symbols, e.g.:\n${text}")
endif()
message(STATUS "runtime symbols: no file streams, iostreams or JSON")
