# cmake -DSOURCE=<fuzz dir> -DBINARY=<build dir> -DCXX=<clang++> -DSECONDS=<n> -P fuzz_smoke.cmake
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE} -B ${BINARY} -DCMAKE_CXX_COMPILER=${CXX}
                        -DCMAKE_BUILD_TYPE=RelWithDebInfo RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "configuring the fuzz targets failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BINARY} -j2 RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "building the fuzz targets failed")
endif()
# Fuzz into a scratch corpus so the checked-in seeds stay as they are.
file(REMOVE_RECURSE ${BINARY}/work)
file(MAKE_DIRECTORY ${BINARY}/work/corpus ${BINARY}/work/artifacts)
execute_process(COMMAND ${BINARY}/fuzz_ingest -max_total_time=${SECONDS} -timeout=10 -rss_limit_mb=2048
                        -artifact_prefix=${BINARY}/work/artifacts/ -print_final_stats=1
                        ${BINARY}/work/corpus ${SOURCE}/corpus
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "the fuzzer found a crash, a leak or a hang: see ${BINARY}/work/artifacts")
endif()
