# Runs one libFuzzer harness: RUNS inputs from seed 1, mutating a fresh copy of the seed corpus, with a 10 s limit per
# input and 2 GB of memory (a hang or a blow-up is a finding, not a wait). Fails, printing the reproducer, on a finding.
# DICT, when not empty: a libFuzzer dictionary of tokens to splice in (tests/fuzz/READER.dict).
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK}/corpus ${WORK}/findings)
set(dict_option "")
if(DICT)
  set(dict_option -dict=${DICT})
endif()
execute_process(COMMAND ${FUZZER} -seed=1 -runs=${RUNS} -timeout=10 -rss_limit_mb=2048 -max_len=65536 ${dict_option}
                        -artifact_prefix=${WORK}/findings/ -print_final_stats=1 ${WORK}/corpus ${SEEDS}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(REGEX MATCH "stat::number_of_executed_units: *[0-9]+" executed "${err}")
string(REGEX MATCH "cov: *[0-9]+" coverage "${err}")
message(STATUS "${FUZZER}: ${executed}, ${coverage}")
if(rc)
  file(GLOB findings ${WORK}/findings/*)
  message(FATAL_ERROR "${FUZZER} found a failure (${rc}); reproduce with: ${FUZZER} ${findings}\n${err}")
endif()
