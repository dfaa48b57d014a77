// slam_mms_merge: drives of one area adjusted into one map (slam_mms_merge/merge_main.hpp).
#include "slam_mms_merge/merge_main.hpp"

int main(int argc, char** argv) { return slam_mms::app::MergeMain(argc, argv); }
