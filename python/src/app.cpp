// slam_mms_run itself (examples/apps/slam_mms_run/run_main.cpp, compiled into the extension): the
// package's `python -m slam_mms run` calls it, so that the command writes exactly the app's files
// from the app's code instead of a second implementation of its output logic.
#include <string>
#include <vector>

#include "common.hpp"
#include "slam_mms_merge/merge_main.hpp"
#include "slam_mms_run/run_main.hpp"

namespace slam_mms::python {
namespace {

// Runs an app's entry point with argv, without the GIL: other Python threads go on; SIGINT/SIGTERM
// reach the app's own handlers (slam_mms_run stops after the current scan and writes what it
// computed), which are put back to Python's when it returns.
int CallApp(int (*entry)(int, const char* const*), const std::vector<std::string>& argv) {
  std::vector<const char*> c_argv;
  c_argv.reserve(argv.size() + 1);
  for (const std::string& a : argv) c_argv.push_back(a.c_str());
  c_argv.push_back(nullptr);
  py::gil_scoped_release release;
  return entry(static_cast<int>(argv.size()), c_argv.data());
}

}  // namespace

void RegisterApp(py::module_& m) {
  m.def(
      "run_app", [](const std::vector<std::string>& argv) { return CallApp(&app::RunMain, argv); },
      py::arg("argv"),
      "Runs slam_mms_run with argv (argv[0] the program name) in this process; returns its exit "
      "status (0 done, 1 input or processing error, 2 bad command line or config, 130/143 "
      "stopped by SIGINT/SIGTERM). Progress goes to stdout, messages to stderr.");
  m.def(
      "merge_app",
      [](const std::vector<std::string>& argv) { return CallApp(&app::MergeMain, argv); },
      py::arg("argv"),
      "Runs slam_mms_merge with argv (argv[0] the program name) in this process; returns its exit "
      "status (0 done, 1 input or processing error, 2 bad command line).");
}

}  // namespace slam_mms::python
