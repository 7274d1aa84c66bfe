# One ctest test per GoogleTest suite of an executable (weft_discover_suites in
# WeftHelpers.cmake). Run by ctest itself, in script mode, before it runs the tests: the
# executable lists its tests (--gtest_list_tests) and this writes CTEST_FILE, one add_test
# per suite with --gtest_filter=Suite.*, when the file is older than the executable.
#
# Why suites and not single tests: a capture or gradient-check test executable loads 180-290
# shared libraries (OpenCV's image codecs bring GDAL and gdcm, its video I/O FFmpeg and
# GStreamer); starting it costs
# 0.3-0.4 s of CPU, while its 188 gradient checks run in 0.1 s and its 233 unit tests in 5 s
# all told. A process per test was most of the unit and gradcheck labels' time.
#
# Input variables: EXE, PREFIX, LABEL, WORKING_DIR, CTEST_FILE, TIMEOUT_S.

execute_process(COMMAND "${EXE}" --gtest_list_tests
  WORKING_DIRECTORY "${WORKING_DIR}" TIMEOUT ${TIMEOUT_S}
  OUTPUT_VARIABLE listing ERROR_VARIABLE errors RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${EXE} --gtest_list_tests failed (${rc}): ${errors}")
endif()

# Suite lines start in column 0 and end their name with a dot ("Camera.",
# "AllOps/Gradcheck.  # TypeParam = ..."); test lines are indented.
string(REPLACE ";" "," listing "${listing}")  # a parameter comment may hold ';'
string(REPLACE "\n" ";" lines "${listing}")
set(script "# Written by cmake/WeftGtestSuites.cmake from ${EXE} --gtest_list_tests.\n")
set(count 0)
foreach(line IN LISTS lines)
  if(line MATCHES "^([A-Za-z0-9_/]+)\\.")
    set(suite "${CMAKE_MATCH_1}")
    # ctest names use '.' between parts; a parametrised suite keeps its '/'.
    set(name "${PREFIX}${suite}")
    string(APPEND script
      "add_test([==[${name}]==] [==[${EXE}]==] [==[--gtest_filter=${suite}.*]==])\n"
      "set_tests_properties([==[${name}]==] PROPERTIES LABELS [==[${LABEL}]==] "
      "WORKING_DIRECTORY [==[${WORKING_DIR}]==])\n")
    math(EXPR count "${count} + 1")
  elseif(line MATCHES "^[^ ]" AND NOT line MATCHES "^Running main\\(\\)")
    message(FATAL_ERROR "${EXE} --gtest_list_tests: cannot read the suite line '${line}'")
  endif()
endforeach()
if(count EQUAL 0)
  message(FATAL_ERROR "${EXE} --gtest_list_tests listed no suite")
endif()
file(WRITE "${CTEST_FILE}.tmp" "${script}")
file(RENAME "${CTEST_FILE}.tmp" "${CTEST_FILE}")
