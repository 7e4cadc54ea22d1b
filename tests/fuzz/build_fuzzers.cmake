# The ctest fixture fuzz_build: configures BUILD_DIR with clang (CXX, CC) and GLASWAVE_FUZZ the
# first time, then builds the fuzzers (only what changed, and through LAUNCHER, ccache, when
# given). Run as `cmake -P` with SOURCE_DIR, BUILD_DIR, CXX, CC and LAUNCHER (may be empty).
function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE output
                  ERROR_VARIABLE output)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${what} failed (${status}):\n${output}")
  endif()
endfunction()

string(TIMESTAMP start "%s")
if(NOT EXISTS ${BUILD_DIR}/CMakeCache.txt)
  set(launcher "")
  if(LAUNCHER)
    set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
  endif()
  run_step("configure the fuzz build" ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${BUILD_DIR}
           -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_C_COMPILER=${CC}
           ${launcher} -DGLASWAVE_FUZZ=ON -DGLASWAVE_TESTS=OFF -DGLASWAVE_PYTHON=OFF)
endif()
cmake_host_system_information(RESULT cores QUERY NUMBER_OF_LOGICAL_CORES)
run_step("build the fuzzers" ${CMAKE_COMMAND} --build ${BUILD_DIR} --target fuzzers -j ${cores})
string(TIMESTAMP end "%s")
math(EXPR seconds "${end} - ${start}")
message(STATUS "the fuzzers are built in ${BUILD_DIR} (${seconds} s)")
