file(REMOVE_RECURSE ${VTEX_SCRATCH})
set(prefix ${VTEX_SCRATCH}/prefix)

function(run_step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "step failed (${status}): ${ARGN}\n${out}")
  endif()
endfunction()

run_step(${CMAKE_COMMAND} --install ${VTEX_BUILD_DIR} --prefix ${prefix})
foreach(installed bin/vtex share/bash-completion/completions/vtex share/man/man1/vtex.1)
  if(NOT EXISTS ${prefix}/${installed})
    message(FATAL_ERROR "${installed} was not installed")
  endif()
endforeach()
run_step(${CMAKE_COMMAND} -S ${VTEX_CONSUMER_SOURCE} -B ${VTEX_SCRATCH}/build
         -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
run_step(${CMAKE_COMMAND} --build ${VTEX_SCRATCH}/build)
run_step(${VTEX_SCRATCH}/build/consumer)
run_step(${CMAKE_COMMAND} -S ${VTEX_CONSUMER_SOURCE} -B ${VTEX_SCRATCH}/build-all
         -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release -DVTEX_ALL=ON)
# A component vtex does not have is refused at configure time, naming it.
file(WRITE ${VTEX_SCRATCH}/bad/CMakeLists.txt
  "cmake_minimum_required(VERSION 3.25)\nproject(bad LANGUAGES CXX)\nfind_package(vtex CONFIG REQUIRED COMPONENTS nosuch)\n")
execute_process(COMMAND ${CMAKE_COMMAND} -S ${VTEX_SCRATCH}/bad -B ${VTEX_SCRATCH}/bad/build -DCMAKE_PREFIX_PATH=${prefix}
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(status EQUAL 0 OR NOT out MATCHES "no component 'nosuch'")
  message(FATAL_ERROR "an unknown component was not refused:\n${out}")
endif()
