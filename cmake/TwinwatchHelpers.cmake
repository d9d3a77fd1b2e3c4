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

# twinwatch_add_tests(<module> [DEPS <targets>...])
#   One GoogleTest executable twinwatch_<module>_tests from every tests/<module>/*_test.cpp.
#   CTest names are "<module>.<Suite>.<Test>", so `ctest -R <module>` selects one module.
function(twinwatch_add_tests module)
  cmake_parse_arguments(ARG "" "" "DEPS" ${ARGN})
  file(GLOB srcs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/${module}/*.cpp)
  add_executable(twinwatch_${module}_tests ${srcs})
  target_link_libraries(twinwatch_${module}_tests PRIVATE ${ARG_DEPS} GTest::gtest GTest::gmock GTest::gtest_main twinwatch_warnings)
  target_include_directories(twinwatch_${module}_tests PRIVATE ${PROJECT_SOURCE_DIR}/tests ${PROJECT_SOURCE_DIR}/src)
  target_compile_definitions(twinwatch_${module}_tests PRIVATE
    TWINWATCH_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    TWINWATCH_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  gtest_discover_tests(twinwatch_${module}_tests DISCOVERY_MODE PRE_TEST TEST_PREFIX "${module}."
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
