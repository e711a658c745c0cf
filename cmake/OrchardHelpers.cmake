# COLMAP-style helpers: one static library per stage folder, one GoogleTest
# executable per *_test.cc beside the code it tests.

# orchard_add_library(NAME SRCS a.cc b.cc DEPS lib1 lib2)
function(orchard_add_library NAME)
  cmake_parse_arguments(ARG "" "" "SRCS;DEPS" ${ARGN})
  add_library(${NAME} STATIC ${ARG_SRCS})
  target_link_libraries(${NAME} PUBLIC ${ARG_DEPS})
  target_compile_options(${NAME} PRIVATE -Wall -Wextra)
endfunction()

# orchard_add_test(NAME SRCS a_test.cc DEPS lib1)
function(orchard_add_test NAME)
  if(NOT ORCHARD_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SRCS;DEPS" ${ARGN})
  add_executable(${NAME} ${ARG_SRCS})
  target_link_libraries(${NAME} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  target_compile_options(${NAME} PRIVATE -Wall -Wextra)
  gtest_discover_tests(${NAME} DISCOVERY_TIMEOUT 60
                       PROPERTIES ENVIRONMENT "ORCHARD_BIN=$<TARGET_FILE_DIR:orchard>/orchard")
endfunction()
