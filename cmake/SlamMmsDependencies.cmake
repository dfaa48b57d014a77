# Every third-party dependency, found once. All come from Debian 12 packages (scripts/install_deps.sh).
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(Ceres 2.1 REQUIRED)
find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs)
find_package(GeographicLib REQUIRED)
find_package(embree 3 REQUIRED)
if(SLAM_MMS_WITH_EGL)
  set(OpenGL_GL_PREFERENCE GLVND)
  find_package(OpenGL REQUIRED COMPONENTS OpenGL EGL)
endif()
find_path(NANOFLANN_INCLUDE_DIR nanoflann.hpp REQUIRED)

# GeographicLib ships only a find module with variables: wrap it in a target we can export.
add_library(slam_mms_geographiclib INTERFACE)
target_link_libraries(slam_mms_geographiclib INTERFACE ${GeographicLib_LIBRARIES})
target_include_directories(slam_mms_geographiclib SYSTEM INTERFACE
  $<BUILD_INTERFACE:${GeographicLib_INCLUDE_DIRS}>)
