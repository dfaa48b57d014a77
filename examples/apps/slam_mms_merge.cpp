// slam_mms_merge: drives of one area adjusted into one map (slam_mms_merge/merge_main.hpp).
#include "app_common/huge_page_malloc.hpp"
#include "slam_mms_merge/merge_main.hpp"

int main(int argc, char** argv) {
  slam_mms::app::ReexecWithHugePageMalloc(argv);
  return slam_mms::app::MergeMain(argc, argv);
}
