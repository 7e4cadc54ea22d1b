# ./scripts/studies --quick (PRODUCT.md section 7) writes every figure, CSV and table, with the
# CSV columns the contract names. Run by ctest as `studies_quick` with
# -DSOURCE_DIR=... -DGLASWAVE=... -DOUT=...; the script builds nothing when GLASWAVE_BINARY is set.
# The studies that need `glaswave brf` may be missing only when that command is refused, which the
# script records in skipped.txt.
file(REMOVE_RECURSE ${OUT})
execute_process(
  COMMAND ${CMAKE_COMMAND} -E env GLASWAVE_BINARY=${GLASWAVE}
          ${SOURCE_DIR}/scripts/studies --quick --out ${OUT}
  RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "scripts/studies --quick failed with ${status}")
endif()

set(skipped "")
if(EXISTS ${OUT}/skipped.txt)
  file(READ ${OUT}/skipped.txt skipped)
  message(STATUS "skipped: ${skipped}")
endif()

function(expect_file name)
  if(NOT EXISTS ${OUT}/${name})
    message(FATAL_ERROR "scripts/studies --quick did not write ${name}")
  endif()
  file(SIZE ${OUT}/${name} size)
  if(size EQUAL 0)
    message(FATAL_ERROR "${name} is empty")
  endif()
endfunction()

function(expect_header name header)
  expect_file(${name})
  file(STRINGS ${OUT}/${name} first LIMIT_COUNT 1)
  string(FIND "${first}" "${header}" at)
  if(NOT at EQUAL 0)
    message(FATAL_ERROR "${name} starts with \"${first}\", expected \"${header}\"")
  endif()
endfunction()

expect_header(table3.csv "parameter,value,tr_pct,cr_pct,gr_pct,seed_tr_pct,seed_cr_pct,seed_gr_pct")
expect_file(table3.md)
expect_file(pai_waveforms.png)
expect_file(slope_waveforms.png)
expect_header(slope.csv "slope_deg,band,rms_width_ns")
expect_header(wi_vpai.csv "vpai,wi")
expect_file(wi_vpai.png)
if(NOT skipped MATCHES "brf_validation")
  expect_header(brf_validation.csv
    "scene,band,brf,brf_stderr,waveform_reflectance,waveform_reflectance_sd")
  expect_file(brf_validation_532.png)
  expect_file(brf_validation_1064.png)
endif()
if(NOT skipped MATCHES "scene")
  expect_file(scene.png)
endif()
