// Registry of `uwbnav` subcommands. Each command lives in its own cli/cmd_*.cpp.
#pragma once

#include <vector>

namespace uwbnav::cli {

struct Command {
  const char* name;
  const char* summary;
  int (*run)(int argc, char** argv);  // argv[0] is the command name
};

// All commands, in help order.
const std::vector<Command>& commands();

}  // namespace uwbnav::cli
