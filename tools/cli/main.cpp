// `uwbnav` host CLI: dispatches subcommands (sim, replay, run, eval, ...).
#include <cstdio>
#include <cstring>

#include "tools/cli/commands.hpp"

namespace {

void usage(std::FILE* f) {
  std::fprintf(f,
               "usage: uwbnav <command> [args]\n"
               "commands:\n");
  for (const auto& c : uwbnav::cli::commands()) std::fprintf(f, "  %-12s %s\n", c.name, c.summary);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "-h") == 0 || std::strcmp(argv[1], "--help") == 0) {
    usage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  for (const auto& c : uwbnav::cli::commands()) {
    if (std::strcmp(argv[1], c.name) == 0) return c.run(argc - 1, argv + 1);
  }
  std::fprintf(stderr, "uwbnav: unknown command '%s'\n", argv[1]);
  usage(stderr);
  return 2;
}
