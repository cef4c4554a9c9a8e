# One fuzz target's smoke run (ctest label fuzz): gathers its seeds (tests/fuzz/seeds/KIND, the shipped files of
# that kind, and ../shared/data's when present: read in place and copied into the build folder only), then fuzzes
# for SECONDS. A crash, sanitizer report, leak, timeout or out-of-memory fails the test; the input that caused it
# is left in WORK_DIR as crash-*, leak-*, timeout-* or oom-*: add it to tests/hostile as a regression case.
# Arguments: FUZZER NAME SOURCE_DIR SHARED_DATA WORK_DIR SECONDS.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR}/corpus ${WORK_DIR}/seeds)
include(${SOURCE_DIR}/tests/fuzz/fuzz_seeds.cmake)
fmpc_fuzz_seed_files(${NAME} ${SOURCE_DIR} ${SHARED_DATA} seeds)
list(LENGTH seeds seed_count)
if(seed_count EQUAL 0)
  message(FATAL_ERROR "no seeds found for fuzz_${NAME}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -DNAME=${NAME} -DSOURCE_DIR=${SOURCE_DIR} -DSHARED_DATA=${SHARED_DATA}
                        -DOUT=${WORK_DIR}/seeds -P ${SOURCE_DIR}/tests/fuzz/copy_seeds.cmake)
set(dictionary ${SOURCE_DIR}/tests/fuzz/dict/${NAME}.dict)
set(dict_arg)
if(EXISTS ${dictionary})
  set(dict_arg -dict=${dictionary})
endif()
# fuzz_python_arguments reads its fixtures from the source tree and keeps the interpreter's objects to the end.
set(extra_args)
if(NAME STREQUAL "python_arguments")
  set(ENV{FMPC_FUZZ_FIXTURES} ${SOURCE_DIR})
  set(ENV{ASAN_OPTIONS} "$ENV{ASAN_OPTIONS}:detect_leaks=0")  # libFuzzer's flag covers the inputs, not the exit
  set(extra_args -detect_leaks=0)
endif()
execute_process(
  COMMAND ${FUZZER} ${dict_arg} ${extra_args} -max_total_time=${SECONDS} -timeout=10 -rss_limit_mb=2048 -max_len=65536
          -print_final_stats=1 -artifact_prefix=${WORK_DIR}/ ${WORK_DIR}/corpus ${WORK_DIR}/seeds
  RESULT_VARIABLE result
  OUTPUT_VARIABLE output
  ERROR_VARIABLE output)
string(REGEX MATCH "stat::number_of_executed_units: *[0-9]+" executed "${output}")
string(REGEX MATCH "cov: [0-9]+ ft: [0-9]+" coverage "${output}")
message("fuzz_${NAME}: ${seed_count} seeds, ${executed}, ${coverage}, exit ${result}")
if(NOT result EQUAL 0)
  message("${output}")
  message(FATAL_ERROR "fuzz_${NAME} found a failing input (see ${WORK_DIR})")
endif()
