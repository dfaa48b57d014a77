#pragma once
// The apps' malloc on transparent huge pages: a drive allocates and frees large buffers all the
// time (scans, range images, surfel slots, submap voxel grids, sort buffers, the final map), and
// each fresh 4 KiB page is a page fault. Where the kernel offers transparent huge pages on request
// ("madvise", Debian's default) glibc (2.35+) asks for them when the tunable
// glibc.malloc.hugetlb=1 is set, which it reads only at process start; so an app's main() calls
// ReexecWithHugePageMalloc first, which starts the same program again with the tunable set.
//
// Measured on this project's 2-core VM (slam_mms_run --mode full, 50 real KITTI frames): page
// faults 146k -> 52k, CPU 8.2 -> 6.8 s (docs/benchmarks.md, session 23). Only in apps' main():
// never in a library or in RunMain (the Python package calls RunMain inside python3).
//
// Not done (the program goes on unchanged) when SLAM_MMS_HUGE_PAGES=0, when GLIBC_TUNABLES already
// names glibc.malloc.hugetlb (the re-executed program, or the user's own choice), when the kernel's
// mode is not "madvise" ("always" needs nothing, "never" offers nothing), with a glibc older than
// 2.35, or when the exec fails.

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

#if defined(__GLIBC__)
#include <gnu/libc-version.h>
#endif

namespace slam_mms::app {

inline void ReexecWithHugePageMalloc(char** argv) {
#if defined(__linux__) && defined(__GLIBC__)
  const char* off = std::getenv("SLAM_MMS_HUGE_PAGES");
  if (off != nullptr && std::strcmp(off, "0") == 0) return;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  const std::string current = tunables != nullptr ? tunables : "";
  if (current.find("glibc.malloc.hugetlb") != std::string::npos) return;
  int major = 0, minor = 0;
  if (std::sscanf(gnu_get_libc_version(), "%d.%d", &major, &minor) != 2 ||
      major * 100 + minor < 235) {
    return;
  }
  std::ifstream mode("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  if (!std::getline(mode, line) || line.find("[madvise]") == std::string::npos) return;
  const std::string value =
      current.empty() ? "glibc.malloc.hugetlb=1" : current + ":glibc.malloc.hugetlb=1";
  if (::setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  ::execv("/proc/self/exe", argv);
  // The exec failed: go on without, and do not leave the tunable for child processes.
  if (tunables != nullptr) {
    ::setenv("GLIBC_TUNABLES", current.c_str(), 1);
  } else {
    ::unsetenv("GLIBC_TUNABLES");
  }
#else
  (void)argv;
#endif
}

}  // namespace slam_mms::app
