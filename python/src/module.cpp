// _slam_mms: the C++ extension of the slam_mms Python package (pybind11). It wraps the SDK and
// never reimplements it; the pure-Python package (python/slam_mms/) adds run_drive, the command
// line and the logging bridge on top.

#include "common.hpp"

PYBIND11_MODULE(_slam_mms, m) {
  m.doc() = "slam_mms C++ SDK bindings (use the slam_mms package).";
  using namespace slam_mms::python;  // NOLINT(google-build-using-namespace)
  RegisterCore(m);
  RegisterOptions(m);
  RegisterReaders(m);
  RegisterMappingSystem(m);
  RegisterEval(m);
  RegisterSim(m);
  RegisterApp(m);
}
