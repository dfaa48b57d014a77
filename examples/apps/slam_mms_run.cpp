// slam_mms_run: the main job (issue 8): a drive in; trajectories, maps, report.json, report.html
// and plots out. Usage: slam_mms_run --help, docs/user_guide.md. The job is app::RunMain
// (slam_mms_run/run_main.cpp), which the Python package's `python -m slam_mms run` runs too.

#include "app_common/huge_page_malloc.hpp"
#include "slam_mms_run/run_main.hpp"

int main(int argc, char** argv) {
  slam_mms::app::ReexecWithHugePageMalloc(argv);
  return slam_mms::app::RunMain(argc, argv);
}
