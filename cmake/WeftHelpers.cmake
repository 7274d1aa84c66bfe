# Precompiled headers. With WEFT_PCH, Eigen, the standard containers (and GoogleTest in the
# tests, CLI11 in apps/) are parsed once per build instead of once per source file. The
# layers share one precompiled header and the test executables another (weft_pch_layer,
# weft_pch_test below): GCC accepts a precompiled header only under the same code-generation
# flags (-fPIC, -march, -fopenmp, -O), which every layer shares and every test shares, and
# each header costs ~10 s of CPU to build. Should the flags ever differ, GCC warns
# (-Winvalid-pch) and parses the headers instead: slower, never wrong.
set(WEFT_PCH_COMMON <vector> <string> <memory> <functional> <Eigen/Core> <Eigen/Geometry>)

# weft_precompile(TARGET HEADERS...): TARGET precompiles these (angle-bracket) headers itself.
function(weft_precompile target)
  if(WEFT_PCH)
    target_precompile_headers(${target} PRIVATE ${ARGN})
  endif()
endfunction()

# weft_pch_holder(NAME PIC HEADERS headers... LIBS libs...): an object library that only
# compiles the precompiled header its users take with weft_shared_pch; PIC and LIBS give it
# their code-generation flags and definitions.
function(weft_pch_holder name pic)
  if(NOT WEFT_PCH)
    return()
  endif()
  cmake_parse_arguments(PARSE_ARGV 2 arg "" "" "HEADERS;LIBS")
  file(CONFIGURE OUTPUT ${CMAKE_BINARY_DIR}/pch/${name}.cpp
    CONTENT "// Compiles the precompiled header of ${name} (cmake/WeftHelpers.cmake).\n")
  add_library(${name} OBJECT ${CMAKE_BINARY_DIR}/pch/${name}.cpp)
  target_link_libraries(${name} PRIVATE weft_options ${arg_LIBS})
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ${pic})
  target_precompile_headers(${name} PRIVATE ${arg_HEADERS})
endfunction()

# weft_shared_pch(TARGET HOLDER): TARGET uses HOLDER's precompiled header.
function(weft_shared_pch target holder)
  if(WEFT_PCH)
    target_precompile_headers(${target} REUSE_FROM ${holder})
  endif()
endfunction()

# weft_unity(TARGET): with WEFT_UNITY_BATCH > 0, the target's sources are compiled
# WEFT_UNITY_BATCH at a time as one translation unit (CMake's unity build): their shared
# headers (GoogleTest, Eigen, nlohmann-json, CLI11) are parsed once per batch. Used for
# the tests and apps/, whose compile time is mostly headers; never for the layers, whose
# optimised code should not depend on which files happen to share a batch. Files of one
# batch share a namespace scope: helpers in an anonymous namespace need names of their
# own (or belong in a shared test header).
function(weft_unity target)
  if(WEFT_UNITY_BATCH GREATER 0)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON
      UNITY_BUILD_MODE BATCH UNITY_BUILD_BATCH_SIZE ${WEFT_UNITY_BATCH})
  endif()
endfunction()

# weft_test_optimisation(TARGET): tests are compiled at -O1 in Release: their own code is
# assertions and small fixtures, the code they test is the layers' (-O3), and -O3 on the
# GoogleTest macros costs compile time that the run never gets back.
function(weft_test_optimisation target)
  set_target_properties(${target} PROPERTIES WEFT_TEST_CODE ON)  # read by weft_options
endfunction()

# weft_layer(NAME DEPS...): a shared library from every .cpp in the current folder.
# Shared, so that ops registered by static initialisers (WEFT_REGISTER_OP) are always
# loaded, whatever the executable happens to reference.
function(weft_layer name)
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  if(sources)
    add_library(${name} SHARED ${sources})
    target_link_libraries(${name} PUBLIC weft_options ${ARGN})
    weft_shared_pch(${name} weft_pch_layer)
  else()  # a layer with no sources yet
    add_library(${name} INTERFACE)
    target_link_libraries(${name} INTERFACE weft_options ${ARGN})
  endif()
endfunction()

# weft_discover_suites(TARGET PREFIX LABEL): one ctest test per GoogleTest suite of TARGET,
# named PREFIX<Suite> and running --gtest_filter=<Suite>.* (cmake/WeftGtestSuites.cmake says
# why). Like gtest_discover_tests' PRE_TEST mode, ctest lists the suites when it starts and
# the executable is newer than the list. One test: `TARGET --gtest_filter=Suite.Name`.
function(weft_discover_suites target prefix label)
  set(dir ${CMAKE_CURRENT_BINARY_DIR})
  set(list_file ${dir}/${target}_suites.cmake)
  set(script ${CMAKE_SOURCE_DIR}/cmake/WeftGtestSuites.cmake)
  file(GENERATE OUTPUT ${dir}/${target}_suites_include.cmake CONTENT
"if(NOT EXISTS [==[$<TARGET_FILE:${target}>]==])
  add_test(${target}_NOT_BUILT ${target}_NOT_BUILT)
  return()
endif()
if(NOT EXISTS [==[${list_file}]==] OR
   NOT [==[${list_file}]==] IS_NEWER_THAN [==[$<TARGET_FILE:${target}>]==] OR
   NOT [==[${list_file}]==] IS_NEWER_THAN [==[${script}]==])
  set(EXE [==[$<TARGET_FILE:${target}>]==])
  set(PREFIX [==[${prefix}]==])
  set(LABEL [==[${label}]==])
  set(WORKING_DIR [==[${dir}]==])
  set(CTEST_FILE [==[${list_file}]==])
  set(TIMEOUT_S 60)
  include([==[${script}]==])
endif()
include([==[${list_file}]==])
")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${dir}/${target}_suites_include.cmake)
endfunction()

# weft_test_folder(LAYER LIBS...): test executables from tests/LAYER/*.cpp, one per
# label. Files ending in _gradcheck_test.cpp are labelled gradcheck,
# _integration_test.cpp integration, any other *_test.cpp unit.
function(weft_test_folder layer)
  set(dir ${CMAKE_CURRENT_SOURCE_DIR}/${layer})
  file(GLOB all CONFIGURE_DEPENDS ${dir}/*_test.cpp)
  file(GLOB helpers CONFIGURE_DEPENDS ${dir}/*.cpp)
  list(FILTER helpers EXCLUDE REGEX "_test\\.cpp$")
  foreach(label unit gradcheck integration)
    set(files "")
    foreach(f ${all})
      if(f MATCHES "_gradcheck_test\\.cpp$")
        set(l gradcheck)
      elseif(f MATCHES "_integration_test\\.cpp$")
        set(l integration)
      else()
        set(l unit)
      endif()
      if(l STREQUAL label)
        list(APPEND files ${f})
      endif()
    endforeach()
    if(files)
      set(target test_${layer}_${label})
      add_executable(${target} ${files} ${helpers})
      target_link_libraries(${target} PRIVATE ${ARGN} GTest::gtest GTest::gtest_main GTest::gmock)
      if(TARGET weft_pch_test AND "weft_graph" IN_LIST ARGN)
        weft_shared_pch(${target} weft_pch_test)
      else()  # not built with the layers' flags (tests/layers reads sources only)
        weft_precompile(${target} ${WEFT_PCH_COMMON} <gtest/gtest.h>)
      endif()
      weft_unity(${target})
      weft_test_optimisation(${target})
      target_compile_definitions(${target} PRIVATE
        WEFT_SOURCE_DIR="${CMAKE_SOURCE_DIR}" WEFT_BINARY_DIR="${CMAKE_BINARY_DIR}")
      if(label STREQUAL "integration")  # long tests: one each, so that ctest -j spreads them
        gtest_discover_tests(${target} TEST_PREFIX "${layer}." DISCOVERY_MODE PRE_TEST
          DISCOVERY_TIMEOUT 60 PROPERTIES LABELS ${label})
      else()
        weft_discover_suites(${target} "${layer}." ${label})
      endif()
    endif()
  endforeach()
endfunction()
