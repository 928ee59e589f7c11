#pragma once
/// Test support: directories for one test process's files under the system's temporary
/// directory (TMPDIR), named <tmp>/rig_<tag>_<pid>. Every directory named here is removed with
/// its contents when the test run ends with no failure; after a failure it is kept and its path
/// is printed, to be looked at. RIG_KEEP_TEST_FILES=1 keeps them always. Defined in
/// tests/catch_main.cc, beside the listener that knows whether the run failed.

#include <string>

namespace nimble::test {

/// The path <tmp>/rig_<tag>_<pid>, not created (for a command that makes it itself); it is
/// removed at the end of the run like scratch_dir's.
std::string scratch_path(const std::string& tag);

/// A fresh, empty directory <tmp>/rig_<tag>_<pid> (anything there before is removed).
std::string scratch_dir(const std::string& tag);

/// The path of file `name` in <tmp>/rig_<tag>_<pid>, the directory made if missing (what is
/// already there stays: one directory for the files of every case of a test file).
std::string scratch_file(const std::string& tag, const std::string& name);

}  // namespace nimble::test
