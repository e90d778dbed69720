// tbdrsim entry point: everything but argument forwarding lives in the core library (sim/app/cli.cpp).
#include <iostream>
#include <string>
#include <vector>

#include "app/host_speed.hpp"
#include "app/cli.hpp"

int main(int argc, char** argv) {
  tbdr::tune_allocator(argv);  // host speed only (app/host_speed.hpp)
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string& line = tbdr::invocation_command_line();
  for (int i = 0; i < argc; ++i) line += (i ? " " : "") + std::string(argv[i]);
  return tbdr::cli_main(args, std::cout, std::cerr);
}
