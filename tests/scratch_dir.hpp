#pragma once
// Scratch folders for tests that write files: one root per test process (ctest runs tests in
// parallel processes), removed when the process exits.
#include <unistd.h>

#include <filesystem>
#include <string>

namespace tbdr::testing_scratch {

namespace fs = std::filesystem;

/// This process's scratch root for a test file, e.g. "sweep" -> /tmp/tbdrsim_test_sweep_<pid>.
inline fs::path scratch_root(const std::string& kind) {
  return fs::temp_directory_path() / ("tbdrsim_test_" + kind + "_" + std::to_string(getpid()));
}

/// Removes a scratch root when destroyed (declare one static instance per test file).
struct ScratchCleanup {
  std::string kind;
  ~ScratchCleanup() {
    std::error_code ec;
    fs::remove_all(scratch_root(kind), ec);
  }
};

/// A fresh, empty folder `name` under the scratch root of `kind`.
inline fs::path scratch_dir(const std::string& kind, const std::string& name) {
  const fs::path dir = scratch_root(kind) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

}  // namespace tbdr::testing_scratch
