# ctest Install.ExampleBuildsAgainstThePackage: installs the build into a scratch prefix,
# then configures, builds and runs examples/sampling-artifact against that prefix only, as a
# user's project would (find_package(reliefsim)). Arguments: BUILD_DIR, EXAMPLE, WORK.
file(REMOVE_RECURSE "${WORK}")
function(rs_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "install check: ${what} failed (${rc})\n${out}\n${err}")
  endif()
endfunction()
rs_step("cmake --install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK}/prefix")
rs_step("configuring the example" ${CMAKE_COMMAND} -S "${EXAMPLE}" -B "${WORK}/build"
        -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=${WORK}/prefix")
rs_step("building the example" ${CMAKE_COMMAND} --build "${WORK}/build" -j 2)
rs_step("running the example's test" "${WORK}/build/sampling_artifact_test")
message(STATUS "install check: the example built against ${WORK}/prefix and passed")
