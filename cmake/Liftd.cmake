# Shared build settings and helper functions for every liftd target.

set(LIFTD_WARNINGS -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion -Wnon-virtual-dtor
                   -Wold-style-cast -Woverloaded-virtual)
if(LIFTD_WERROR)
  list(APPEND LIFTD_WARNINGS -Werror)
endif()

if(LIFTD_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()

if(LIFTD_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "LIFTD_FUZZ needs clang (use the 'fuzz' preset)")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
  add_custom_target(fuzzers)
endif()

# liftd_add_subdirectories(<dir>): add every immediate subfolder of <dir> that has a CMakeLists.txt.
function(liftd_add_subdirectories dir)
  file(GLOB children LIST_DIRECTORIES true RELATIVE ${CMAKE_CURRENT_SOURCE_DIR}/${dir} ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/*)
  list(SORT children)
  foreach(child IN LISTS children)
    if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/${child}/CMakeLists.txt)
      add_subdirectory(${dir}/${child})
    endif()
  endforeach()
endfunction()

# Precompiled headers (LIFTD_PCH). Two hosts compile the headers once each; the targets reuse
# them (REUSE_FROM), so every user must compile with the host's flags: the same warnings and, for
# the tests, the same test options. Position-independent code is the compiler's default (PIE)
# everywhere, for the same reason. GCC refuses a header compiled with other flags, and CMake's
# -Winvalid-pch with -Werror makes that a build error, never a silent slow build.
#   liftd_pch_app    nlohmann-json and Asio: the API, config, daemon and tool targets (PCH)
#   liftd_pch_tests  GoogleTest, GoogleMock, nlohmann-json and Asio: every test binary
function(liftd_add_pch_hosts)
  if(NOT LIFTD_PCH OR NOT LIFTD_UNITY_BUILD)
    return()
  endif()
  set(common <nlohmann/json.hpp> <asio.hpp> <algorithm> <array> <chrono> <cstdint> <filesystem>
             <functional> <map> <optional> <string> <string_view> <thread> <vector>)
  add_library(liftd_pch_app OBJECT ${PROJECT_SOURCE_DIR}/cmake/pch_host.cpp)
  target_compile_options(liftd_pch_app PRIVATE ${LIFTD_WARNINGS})
  target_link_libraries(liftd_pch_app PRIVATE nlohmann_json::nlohmann_json)
  target_precompile_headers(liftd_pch_app PRIVATE ${common})
  if(LIFTD_TESTS)
    add_library(liftd_pch_tests OBJECT ${PROJECT_SOURCE_DIR}/cmake/pch_host.cpp)
    target_compile_options(liftd_pch_tests PRIVATE ${LIFTD_WARNINGS} ${LIFTD_TEST_COMPILE_OPTIONS})
    target_link_libraries(liftd_pch_tests PRIVATE nlohmann_json::nlohmann_json GTest::gtest GTest::gmock)
    target_precompile_headers(liftd_pch_tests PRIVATE <gtest/gtest.h> <gmock/gmock.h> ${common})
  endif()
endfunction()

# liftd_use_pch(<target> <host>): <target> reuses the host's precompiled headers, if there is one.
function(liftd_use_pch target host)
  if(TARGET ${host})
    target_precompile_headers(${target} REUSE_FROM ${host})
  endif()
endfunction()

# liftd_kind_libraries(<out> <part>): liftd::<kind>_<part> of every kind in LIFTD_DRIVE_KINDS
# (part: config, commands, host), for the targets that put the kinds together.
function(liftd_kind_libraries out part)
  set(libs "")
  foreach(kind IN LISTS LIFTD_DRIVE_KINDS)
    list(APPEND libs liftd::${kind}_${part})
  endforeach()
  set(${out} ${libs} PARENT_SCOPE)
endfunction()

# liftd_library(<name> SOURCES ... [DEPS ...] [PCH]): a static library liftd_<name> with the
# project's warnings, the lib/ folder as include root (#include "dcp/frame.hpp") and alias
# liftd::<name>. PCH: it uses nlohmann-json or Asio and reuses their precompiled headers.
function(liftd_library name)
  cmake_parse_arguments(ARG "PCH" "" "SOURCES;DEPS" ${ARGN})
  add_library(liftd_${name} STATIC ${ARG_SOURCES})
  add_library(liftd::${name} ALIAS liftd_${name})
  target_include_directories(liftd_${name} PUBLIC ${PROJECT_SOURCE_DIR}/lib)
  target_compile_options(liftd_${name} PRIVATE ${LIFTD_WARNINGS})
  target_link_libraries(liftd_${name} PUBLIC ${ARG_DEPS})
  if(ARG_PCH)
    liftd_use_pch(liftd_${name} liftd_pch_app)
  endif()
endfunction()

# liftd_executable(<name> SOURCES ... [DEPS ...] [INSTALL] [PCH]): a program in build/bin.
function(liftd_executable name)
  cmake_parse_arguments(ARG "INSTALL;PCH" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_compile_options(${name} PRIVATE ${LIFTD_WARNINGS})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  if(ARG_PCH)
    liftd_use_pch(${name} liftd_pch_app)
  endif()
  if(ARG_INSTALL)
    install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endfunction()

# The test tiers (the table of test labels in README.md): every test carries exactly one of them.
#   unit     in-process, on a fake clock or with no time at all
#   process  starts a process, opens a pty or a socket, or waits on real time
#   slow     a long real-time end-to-end run, about a minute or more (not in the sanitizer run)
set(LIFTD_TEST_TIERS unit process slow)

# liftd_check_tier(<name> <labels...>): stops the configure step unless exactly one tier is given.
function(liftd_check_tier name)
  set(tiers "")
  foreach(label IN LISTS ARGN)
    if(label IN_LIST LIFTD_TEST_TIERS)
      list(APPEND tiers ${label})
    endif()
  endforeach()
  list(LENGTH tiers count)
  if(NOT count EQUAL 1)
    list(JOIN LIFTD_TEST_TIERS ", " all)
    list(JOIN tiers ", " given)
    message(FATAL_ERROR "test ${name}: give exactly one tier label (${all}), not '${given}'")
  endif()
endfunction()

# liftd_test(<name> SOURCES ... [DEPS ...] LABELS <tier> ... [RUN_SERIAL]): a GoogleTest binary
# whose cases are registered with CTest one by one, each carrying every label given (so
# `ctest -LE slow` works): exactly one tier, the kind (dcp, sch001, uss) where it tests one, and
# its folder's labels; RUN_SERIAL: each case runs with no other test beside it.
function(liftd_test name)
  cmake_parse_arguments(ARG "RUN_SERIAL" "" "SOURCES;DEPS;LABELS" ${ARGN})
  liftd_check_tier(${name} ${ARG_LABELS})
  if(NOT LIFTD_TESTS)
    return()
  endif()
  set(serial FALSE)
  if(ARG_RUN_SERIAL)
    set(serial TRUE)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_compile_options(${name} PRIVATE ${LIFTD_WARNINGS} ${LIFTD_TEST_COMPILE_OPTIONS})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gmock GTest::gtest_main)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  liftd_use_pch(${name} liftd_pch_tests)
  # Test binaries with many sources would otherwise be one unity file of a minute or more
  # (api_test: 85 s under the sanitizers), compiled on one core at the end of the build while
  # the other waits: in batches of four they compile side by side.
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests
                                           UNITY_BUILD_BATCH_SIZE 4)
  # gtest_discover_tests expands its PROPERTIES list three more times before it writes the test
  # file; the separators between labels are escaped for each of those expansions.
  string(REPLACE ";" "\\\\\\\\\\\\\\;" labels "${ARG_LABELS}")
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
                       PROPERTIES LABELS "${labels}" TIMEOUT 300 RUN_SERIAL ${serial})
endfunction()

# liftd_test_library(<name> SOURCES ... [DEPS ...]): code several test binaries share, compiled
# once, like the tests (their options, the tests/ include root, GoogleTest).
function(liftd_test_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  if(NOT LIFTD_TESTS)
    return()
  endif()
  add_library(${name} STATIC ${ARG_SOURCES})
  target_compile_options(${name} PRIVATE ${LIFTD_WARNINGS} ${LIFTD_TEST_COMPILE_OPTIONS})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} GTest::gtest)
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR}/tests ${PROJECT_SOURCE_DIR}/lib)
  liftd_use_pch(${name} liftd_pch_tests)
endfunction()

# liftd_test_runs_liftctl(<name>): the test binary <name> runs the liftctl program: built before
# it, its path in LIFTCTL_PATH (tests/api/test_support.hpp's LiftctlFixture).
function(liftd_test_runs_liftctl name)
  if(NOT TARGET ${name})
    return()
  endif()
  add_dependencies(${name} liftctl)
  target_compile_definitions(${name} PRIVATE LIFTCTL_PATH="$<TARGET_FILE:liftctl>")
endfunction()

# liftd_fuzzer(<name> SOURCES ... [DEPS ...] [LABELS ...]): a libFuzzer target, built only with
# LIFTD_FUZZ, run for LIFTD_FUZZ_SECONDS under ctest with the labels "fuzz", "unit" (in-process,
# no clock) and those given (its kind); tests/ is an include root, as for the tests (the API
# targets share tests/api/handler_fuzz.hpp and the fakes). Its committed seed corpus is
# tests/fuzz/corpus/<name>/ (required: replayed first on every run, so a crash input kept there
# is a regression test) and its dictionary tests/fuzz/dict/<name>.dict (optional). New inputs go
# to <build>/fuzz/corpus/<name>/, never into the source tree; tools/fuzz.sh runs campaigns.
function(liftd_fuzzer name)
  if(NOT LIFTD_FUZZ)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  set(seeds ${PROJECT_SOURCE_DIR}/tests/fuzz/corpus/${name})
  set(dict ${PROJECT_SOURCE_DIR}/tests/fuzz/dict/${name}.dict)
  if(NOT IS_DIRECTORY ${seeds})
    message(FATAL_ERROR "fuzz target ${name} has no seed corpus: add tests/fuzz/corpus/${name}/ "
                        "(see tests/fuzz/README.md)")
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_link_options(${name} PRIVATE -fsanitize=fuzzer)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/fuzz)
  add_dependencies(fuzzers ${name})
  set(args -max_total_time=${LIFTD_FUZZ_SECONDS} -seed=1 -print_final_stats=1)
  if(EXISTS ${dict})
    list(APPEND args -dict=${dict})
  endif()
  set(work ${CMAKE_BINARY_DIR}/fuzz/corpus/${name})
  file(MAKE_DIRECTORY ${work})
  add_test(NAME ${name} COMMAND ${name} ${args} ${work} ${seeds})
  set_tests_properties(${name} PROPERTIES LABELS "fuzz;unit;${ARG_LABELS}" TIMEOUT 600)
endfunction()

# liftd_write_drive_kinds(<file> <kind>...): the X-macro lib/drive/drive.hpp makes drive::Kind
# and drive::kKindNames from, one row per kind in the list's order: X(Dcp, "dcp"); and beside it
# kinds.txt, a kind a line, for the scripts (tools/test.sh soaks each). Rewritten only when the
# list changes, so a configure run rebuilds nothing otherwise.
function(liftd_write_drive_kinds file)
  set(rows "")
  foreach(kind IN LISTS ARGN)
    if(NOT kind MATCHES "^[a-z][a-z0-9]*$")
      message(FATAL_ERROR "LIFTD_DRIVE_KINDS: \"${kind}\" is not a folder name of lower-case "
                          "letters and digits beginning with a letter")
    endif()
    string(SUBSTRING ${kind} 0 1 first)
    string(TOUPPER ${first} first)
    string(SUBSTRING ${kind} 1 -1 rest)
    string(APPEND rows " \\\n  X(${first}${rest}, \"${kind}\")")
  endforeach()
  set(text "// Made by liftd_write_drive_kinds (cmake/Liftd.cmake) from LIFTD_DRIVE_KINDS of the top\n")
  string(APPEND text "// CMakeLists.txt; lib/drive/drive.hpp includes it. Not to be edited.\n")
  string(APPEND text "#define LIFTD_FOR_EACH_DRIVE_KIND(X)${rows}\n")
  file(CONFIGURE OUTPUT ${file} CONTENT "${text}" @ONLY)
  get_filename_component(dir ${file} DIRECTORY)
  list(JOIN ARGN "\n" lines)
  file(CONFIGURE OUTPUT ${dir}/kinds.txt CONTENT "${lines}\n" @ONLY)
endfunction()
