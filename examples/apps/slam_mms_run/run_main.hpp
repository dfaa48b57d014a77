#pragma once
// RunMain: the whole of slam_mms_run (command line in, files in --out, exit status out; see
// run_main.cpp's header comment for the interface). main() calls it; so does the Python package
// (python -m slam_mms run), so that both write the same files from the same code.
//
// For the duration of the call it installs its SIGINT/SIGTERM handlers and its stderr log sink
// and puts the previous ones back before it returns. It prints progress to stdout and messages to
// stderr (it is an application entry point, not library code). Not reentrant: one call at a time
// per process.

namespace slam_mms::app {

/// Runs slam_mms_run with `argv` (argv[0] the program name). Returns the exit status: 0 done, 1 an
/// input or processing error, 2 a bad command line or config file, 128 + signal when stopped by
/// SIGINT/SIGTERM.
int RunMain(int argc, const char* const* argv);

}  // namespace slam_mms::app
