# Helpers that keep each module's CMakeLists.txt to a couple of lines.

# twinwatch_add_module(<name> [DEPS <targets>...])
#   Library twinwatch_<name> (alias twinwatch::<name>) from every src/<name>/*.cpp.
function(twinwatch_add_module name)
  cmake_parse_arguments(ARG "" "" "DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB srcs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/${name}/*.cpp)
  add_library(twinwatch_${name} STATIC ${srcs})
  add_library(twinwatch::${name} ALIAS twinwatch_${name})
  target_include_directories(twinwatch_${name}
    PUBLIC ${PROJECT_SOURCE_DIR}/include ${PROJECT_BINARY_DIR}/generated
    PRIVATE ${PROJECT_SOURCE_DIR}/src)
  target_compile_features(twinwatch_${name} PUBLIC cxx_std_20)
  target_link_libraries(twinwatch_${name} PUBLIC ${ARG_DEPS} PRIVATE twinwatch_warnings ${ARG_PRIVATE_DEPS})
  set_target_properties(twinwatch_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
endfunction()

# twinwatch_add_tests(<module> [DEPS <targets>...] [ONE_PROCESS <Suite>[:<shards>]...])
#   One GoogleTest executable twinwatch_<module>_tests from every tests/<module>/*_test.cpp.
#   CTest names are "<module>.<Suite>.<Test>", so `ctest -R <module>` selects one module.
#   Each test runs in a process of its own, which rebuilds its suite's fixture (SetUpTestSuite):
#   the suites named in ONE_PROCESS, whose fixture simulates and identifies a reference twin, run
#   instead as one CTest test "<module>.<Suite>" (or <shards> of them, "<module>.<Suite>/<k>", gtest's
#   own sharding), so the fixture is built once per process: MonitorLoop's 48 tests took 597 s of
#   processes one by one and take 124 s in two shards. One test of such a suite alone:
#   build/tests/<module>/twinwatch_<module>_tests --gtest_filter=<Suite>.<Test>
#   They are scheduled first (COST), so that a clean build's first run does not end on them.
function(twinwatch_add_tests module)
  cmake_parse_arguments(ARG "" "" "DEPS;ONE_PROCESS" ${ARGN})
  file(GLOB srcs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/${module}/*.cpp)
  add_executable(twinwatch_${module}_tests ${srcs})
  target_link_libraries(twinwatch_${module}_tests PRIVATE ${ARG_DEPS} GTest::gtest GTest::gmock GTest::gtest_main twinwatch_warnings)
  target_include_directories(twinwatch_${module}_tests PRIVATE ${PROJECT_SOURCE_DIR}/tests ${PROJECT_SOURCE_DIR}/src)
  target_compile_definitions(twinwatch_${module}_tests PRIVATE
    TWINWATCH_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    TWINWATCH_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  set(excluded "")
  foreach(entry IN LISTS ARG_ONE_PROCESS)
    string(REPLACE ":" ";" parts "${entry}")
    list(GET parts 0 suite)
    list(LENGTH parts n)
    set(shards 1)
    if(n GREATER 1)
      list(GET parts 1 shards)
    endif()
    string(APPEND excluded ":${suite}.*")
    math(EXPR last "${shards} - 1")
    foreach(k RANGE ${last})
      set(name ${module}.${suite})
      if(shards GREATER 1)
        set(name ${name}/${k})
      endif()
      add_test(NAME ${name} COMMAND twinwatch_${module}_tests --gtest_filter=${suite}.* WORKING_DIRECTORY ${PROJECT_BINARY_DIR})
      set_tests_properties(${name} PROPERTIES TIMEOUT 900 COST 1000 ENVIRONMENT "GTEST_TOTAL_SHARDS=${shards};GTEST_SHARD_INDEX=${k}")
    endforeach()
  endforeach()
  set(filter "")
  if(NOT excluded STREQUAL "")
    string(SUBSTRING "${excluded}" 1 -1 excluded)
    set(filter TEST_FILTER "-${excluded}")
  endif()
  gtest_discover_tests(twinwatch_${module}_tests DISCOVERY_MODE PRE_TEST TEST_PREFIX "${module}." ${filter}
    WORKING_DIRECTORY ${PROJECT_BINARY_DIR} PROPERTIES TIMEOUT 600)
endfunction()

# twinwatch_add_benchmark(<file.cpp> [DEPS <targets>...])
function(twinwatch_add_benchmark src)
  cmake_parse_arguments(ARG "" "" "DEPS" ${ARGN})
  get_filename_component(stem ${src} NAME_WE)
  add_executable(${stem} ${src})
  target_link_libraries(${stem} PRIVATE ${ARG_DEPS} benchmark::benchmark twinwatch_warnings)
  target_compile_definitions(${stem} PRIVATE TWINWATCH_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
endfunction()
