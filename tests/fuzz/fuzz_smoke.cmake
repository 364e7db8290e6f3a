# cmake -DSOURCE=<fuzz dir> -DBINARY=<build dir> -DCXX=<clang++>
#       -DRUNS=<target>:<corpus folder>:<runs>[;...] -DSECONDS=<cap per target> -P fuzz_smoke.cmake
#
# A fixed seed and a fixed number of runs: each fuzzer replays its seed corpus (the regression
# inputs included), then mutates for a bounded, alike (not bit-identical: coverage feedback
# varies between runs) amount of work. Open-ended fuzzing is fuzz/README.md's campaign.
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE} -B ${BINARY} -DCMAKE_CXX_COMPILER=${CXX}
                        -DCMAKE_BUILD_TYPE=RelWithDebInfo RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "configuring the fuzz targets failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BINARY} -j2 RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "building the fuzz targets failed")
endif()
foreach(run IN LISTS RUNS)
  string(REPLACE ":" ";" fields "${run}")
  list(GET fields 0 target)
  list(GET fields 1 corpus)
  list(GET fields 2 runs)
  # Fuzz into a scratch corpus so the checked-in seeds stay as they are.
  set(work ${BINARY}/work/${target})
  file(REMOVE_RECURSE ${work})
  file(MAKE_DIRECTORY ${work}/corpus ${work}/artifacts)
  execute_process(COMMAND ${BINARY}/${target} -seed=1 -runs=${runs} -max_total_time=${SECONDS} -timeout=10
                          -rss_limit_mb=2048 -artifact_prefix=${work}/artifacts/ -print_final_stats=1
                          ${work}/corpus ${SOURCE}/${corpus}
                  RESULT_VARIABLE status)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${target} found a crash, a leak, a hang or an out-of-memory input: see ${work}/artifacts")
  endif()
endforeach()
