file(REMOVE_RECURSE ${VTEX_SCRATCH})
set(prefix ${VTEX_SCRATCH}/prefix)

function(run_step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "step failed (${status}): ${ARGN}\n${out}")
  endif()
endfunction()

run_step(${CMAKE_COMMAND} --install ${VTEX_BUILD_DIR} --prefix ${prefix})
if(NOT EXISTS ${prefix}/bin/vtex)
  message(FATAL_ERROR "the vtex program was not installed")
endif()
run_step(${CMAKE_COMMAND} -S ${VTEX_CONSUMER_SOURCE} -B ${VTEX_SCRATCH}/build
         -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
run_step(${CMAKE_COMMAND} --build ${VTEX_SCRATCH}/build)
run_step(${VTEX_SCRATCH}/build/consumer)
