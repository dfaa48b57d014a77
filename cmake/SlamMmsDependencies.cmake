# Every third-party dependency, found once. All come from Debian 12 packages (scripts/install_deps.sh).
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(Ceres 2.1 REQUIRED)
# Plots and simulator pictures are drawn with OpenCV (core, imgproc); imgcodecs only reads PNGs
# back in the tests (the library writes them with libpng, io, private).
find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs)
find_package(PNG REQUIRED)
find_package(GeographicLib REQUIRED)
find_package(embree 3 REQUIRED)
if(SLAM_MMS_WITH_EGL)
  set(OpenGL_GL_PREFERENCE GLVND)
  find_package(OpenGL REQUIRED COMPONENTS OpenGL EGL)
endif()
find_path(NANOFLANN_INCLUDE_DIR nanoflann.hpp REQUIRED)
# extrinsics.yaml of a drive folder (io, private).
find_package(yaml-cpp REQUIRED)
# Output coordinate reference systems (io, private): PROJ 9 (Debian libproj-dev).
find_package(PROJ 9 REQUIRED CONFIG)
# Every JSON read and written (report.json, georef.json, ...): nlohmann-json (header-only).
find_package(nlohmann_json 3.11 REQUIRED)

# GeographicLib ships only a find module with variables: wrap it in a target we can export.
add_library(slam_mms_geographiclib INTERFACE)
target_link_libraries(slam_mms_geographiclib INTERFACE ${GeographicLib_LIBRARIES})
target_include_directories(slam_mms_geographiclib SYSTEM INTERFACE
  $<BUILD_INTERFACE:${GeographicLib_INCLUDE_DIRS}>)

# ROS 1 bag storage for the optional rosbag module. Debian's catkin-generated
# rosbag_storageConfig.cmake pulls pluginlib -> ament_cmake_core, which runs the first `python3` on
# PATH and fails without ament_package; the headers and libraries are therefore found directly and
# wrapped, with absolute paths, in an INTERFACE target that exports cleanly (as GeographicLib): a
# consumer of the installed static library needs no ROS CMake files.
if(SLAM_MMS_WITH_ROSBAG)
  set(_rosbag_missing "")
  foreach(_h rosbag/bag.h rosbag/view.h sensor_msgs/PointCloud2.h sensor_msgs/Imu.h
             sensor_msgs/NavSatFix.h geometry_msgs/TwistStamped.h ros/time.h)
    string(MAKE_C_IDENTIFIER "${_h}" _v)
    find_path(SLAM_MMS_ROS_INC_${_v} ${_h})
    if(NOT SLAM_MMS_ROS_INC_${_v})
      list(APPEND _rosbag_missing ${_h})
    endif()
  endforeach()
  # rosbag/bag.h includes <pluginlib/class_loader.hpp> and the ROS 2 style headers below it, which
  # Debian installs one folder down (/usr/include/<package>/<package>/...).
  set(_rosbag_inc_dirs "")
  foreach(_h pluginlib/class_loader.hpp class_loader/class_loader.hpp
             ament_index_cpp/get_package_prefix.hpp rcpputils/filesystem_helper.hpp
             rcutils/types.h)
    string(REGEX REPLACE "/.*" "" _pkg "${_h}")
    find_path(SLAM_MMS_ROS_INC_${_pkg} ${_h} PATH_SUFFIXES ${_pkg})
    if(SLAM_MMS_ROS_INC_${_pkg})
      list(APPEND _rosbag_inc_dirs ${SLAM_MMS_ROS_INC_${_pkg}})
    else()
      list(APPEND _rosbag_missing ${_h})
    endif()
  endforeach()
  set(_rosbag_libs "")
  foreach(_l rosbag_storage roscpp_serialization rostime cpp_common console_bridge)
    find_library(SLAM_MMS_ROS_LIB_${_l} ${_l})
    if(SLAM_MMS_ROS_LIB_${_l})
      list(APPEND _rosbag_libs ${SLAM_MMS_ROS_LIB_${_l}})
    else()
      list(APPEND _rosbag_missing lib${_l})
    endif()
  endforeach()
  if(_rosbag_missing)
    message(STATUS "slam_mms: SLAM_MMS_WITH_ROSBAG: not found: ${_rosbag_missing}; the rosbag "
                   "module is skipped (apt-get install librosbag-storage-dev libsensor-msgs-dev, "
                   "or -DSLAM_MMS_WITH_ROSBAG=OFF)")
    set(SLAM_MMS_WITH_ROSBAG OFF)
  else()
    list(REMOVE_DUPLICATES _rosbag_inc_dirs)
    add_library(slam_mms_rosbag_deps INTERFACE)
    target_link_libraries(slam_mms_rosbag_deps INTERFACE ${_rosbag_libs})
    target_include_directories(slam_mms_rosbag_deps SYSTEM INTERFACE
      "$<BUILD_INTERFACE:${_rosbag_inc_dirs}>")
  endif()
endif()
