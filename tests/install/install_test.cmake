# `cmake --install` into a scratch prefix, then what a user does with it: the package's files are
# there, the example is configured and built against it from a copy outside the source tree and
# run (it checks its shot against the closed form), a consumer that sets no C++ standard of its own
# builds and runs (tests/install/consumer), the installed command runs, and the installed
# Python module imports. Run by ctest as `cmake -P` with BINARY_DIR, SOURCE_DIR, WORK_DIR, LIBDIR,
# COMPILER, LAUNCHER (may be empty), PYTHON (empty: no module) and PYTHON_DIR.
function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE output
                  ERROR_VARIABLE output)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${what} failed (${status}):\n${output}")
  endif()
  message(STATUS "${what}: ok")
  set(step_output "${output}" PARENT_SCOPE)
endfunction()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
run_step("install" ${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${prefix})

foreach(path bin/glaswave libexec/glaswave/glaswave-read-granule
        libexec/glaswave/glaswave-read-voxels libexec/glaswave/glaswave-read-retrieval-input
        include/glaswave/glaswave.hpp include/glaswave/core/error.hpp
        include/glaswave/pipeline/engine/run.hpp ${LIBDIR}/libglaswave_engine.a
        ${LIBDIR}/cmake/glaswave/glaswaveConfig.cmake
        ${LIBDIR}/cmake/glaswave/glaswaveConfigVersion.cmake
        ${LIBDIR}/cmake/glaswave/glaswaveTargets.cmake share/glaswave/presets/glas.json
        share/glaswave/demo/demo.json share/glaswave/plots/plot_products.py)
  if(NOT EXISTS ${prefix}/${path})
    message(FATAL_ERROR "the install has no ${path}")
  endif()
endforeach()

# The example from a copy of examples/, so that nothing of the source tree is near it.
file(COPY ${SOURCE_DIR}/examples/ DESTINATION ${WORK_DIR}/example-source)
set(launcher "")
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
run_step("configure the example" ${CMAKE_COMMAND} -S ${WORK_DIR}/example-source
         -B ${WORK_DIR}/example-build -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix}
         -DCMAKE_CXX_COMPILER=${COMPILER} ${launcher} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
file(STRINGS ${WORK_DIR}/example-build/CMakeCache.txt package_dir REGEX "^glaswave_DIR:")
if(NOT package_dir STREQUAL "glaswave_DIR:PATH=${prefix}/${LIBDIR}/cmake/glaswave")
  message(FATAL_ERROR "the example found another glaswave: ${package_dir}")
endif()
run_step("build the example" ${CMAKE_COMMAND} --build ${WORK_DIR}/example-build)
run_step("run the example" ${WORK_DIR}/example-build/one_shot)
message(STATUS "${step_output}")

# A consumer that sets no language standard: the package's target must carry C++20 itself.
file(COPY ${SOURCE_DIR}/tests/install/consumer/ DESTINATION ${WORK_DIR}/consumer-source)
run_step("configure a consumer without a standard" ${CMAKE_COMMAND} -S ${WORK_DIR}/consumer-source
         -B ${WORK_DIR}/consumer-build -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix}
         -DCMAKE_CXX_COMPILER=${COMPILER} ${launcher} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
run_step("build the consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/consumer-build)
run_step("run the consumer" ${WORK_DIR}/consumer-build/consumer)
message(STATUS "${step_output}")

run_step("the installed command" ${prefix}/bin/glaswave --version)
if(PYTHON)
  run_step("import the installed module" ${CMAKE_COMMAND} -E env
           PYTHONPATH=${prefix}/${PYTHON_DIR} PYTHONDONTWRITEBYTECODE=1 ${PYTHON} -c
           "import glaswave, sys; assert glaswave.__file__.startswith(sys.argv[1]); print(glaswave.__version__)"
           ${prefix})
endif()
file(REMOVE_RECURSE ${WORK_DIR})
