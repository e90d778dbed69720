#pragma once
// Tests' way to run the command line in-process: `tbdrsim ARGS...` through cli_main, with its exit
// code and what it printed.
#include <sstream>
#include <string>
#include <vector>

#include "app/cli.hpp"

namespace tbdr::testing_support {

/// What one `tbdrsim` command returned and printed.
struct CliResult {
  int code;
  std::string out;
  std::string err;
};

/// Runs `tbdrsim args...` in this process.
inline CliResult run_cli(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int code = cli_main(args, out, err);
  return {code, out.str(), err.str()};
}

}  // namespace tbdr::testing_support
