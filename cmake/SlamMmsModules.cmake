# slam_mms is built from one static library per module (src/<module>/*.cpp), so each module and its
# tests build on their own; slam_mms (INTERFACE) links them all for users.
set(SLAM_MMS_MODULES "" CACHE INTERNAL "")

set(SLAM_MMS_WARNINGS -Wall -Wextra -Wpedantic -Wno-unused-parameter)

function(slam_mms_add_module name)
  cmake_parse_arguments(M "" "" "DEPS;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  file(GLOB _src CONFIGURE_DEPENDS "${PROJECT_SOURCE_DIR}/src/${name}/*.cpp")
  if(NOT _src)
    return()
  endif()
  set(target slam_mms_${name})
  add_library(${target} STATIC ${_src})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name}
                                             CXX_VISIBILITY_PRESET hidden
                                             VISIBILITY_INLINES_HIDDEN ON)
  target_include_directories(${target}
    PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>
           $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/generated>
           $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
    PRIVATE ${PROJECT_SOURCE_DIR}/src)
  target_include_directories(${target} SYSTEM PRIVATE ${NANOFLANN_INCLUDE_DIR})
  foreach(d IN LISTS M_DEPS)
    if(TARGET slam_mms_${d})
      target_link_libraries(${target} PUBLIC slam_mms_${d})
    endif()
  endforeach()
  target_link_libraries(${target} PUBLIC ${M_PUBLIC_LIBS} PRIVATE ${M_PRIVATE_LIBS})
  target_compile_options(${target} PRIVATE ${SLAM_MMS_WARNINGS})
  set(SLAM_MMS_MODULES ${SLAM_MMS_MODULES} ${name} CACHE INTERNAL "")
endfunction()

# One test executable per tests/<module>/<name>_test.cpp, named <module>_<name>_test.
function(slam_mms_add_module_tests name)
  file(GLOB _tests CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/${name}/*_test.cpp")
  if(NOT TARGET slam_mms_${name})
    return()
  endif()
  foreach(t IN LISTS _tests)
    get_filename_component(base ${t} NAME_WE)
    set(exe ${name}_${base})
    add_executable(${exe} ${t})
    target_link_libraries(${exe} PRIVATE slam_mms_${name} ${SLAM_MMS_TEST_EXTRA_${name}} slam_mms_testing
                                         GTest::gtest_main GTest::gmock)
    target_include_directories(${exe} PRIVATE ${PROJECT_SOURCE_DIR}/src ${CMAKE_CURRENT_SOURCE_DIR})
    target_include_directories(${exe} SYSTEM PRIVATE ${NANOFLANN_INCLUDE_DIR})
    target_compile_options(${exe} PRIVATE ${SLAM_MMS_WARNINGS})
    gtest_discover_tests(${exe} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
                         PROPERTIES LABELS ${name})
  endforeach()
endfunction()
