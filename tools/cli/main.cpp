// `uwbnav` host CLI: dispatches subcommands (sim, replay, run, eval, ...);
// `uwbnav help [CMD]` and `uwbnav CMD --help` print usage on stdout and exit 0.
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <vector>

#include "tools/cli/commands.hpp"

namespace {

void usage(std::FILE* f) {
  std::fprintf(f,
               "usage: uwbnav <command> [args]      (uwbnav help COMMAND, uwbnav COMMAND --help)\n"
               "commands:\n");
  for (const auto& c : uwbnav::cli::commands()) std::fprintf(f, "  %-12s %s\n", c.name, c.summary);
}

bool is_help(const char* a) { return std::strcmp(a, "--help") == 0 || std::strcmp(a, "-h") == 0; }

const uwbnav::cli::Command* find_command(const char* name) {
  for (const auto& c : uwbnav::cli::commands()) {
    if (std::strcmp(name, c.name) == 0) return &c;
  }
  return nullptr;
}

// Usage of one command on stdout, exit 0: the command is run with its
// subcommand (eval report ...) and --help only, which every command answers
// with its usage text (on stderr, redirected to stdout here) before doing anything.
int command_help(const uwbnav::cli::Command& c, const char* sub) {
  static char help_arg[] = "--help";
  std::vector<char*> args{const_cast<char*>(c.name)};
  if (sub != nullptr && sub[0] != '-') args.push_back(const_cast<char*>(sub));
  args.push_back(help_arg);
  std::fflush(stdout);
  std::fflush(stderr);
  if (::dup2(STDOUT_FILENO, STDERR_FILENO) < 0) return 1;
  (void)c.run(static_cast<int>(args.size()), args.data());
  std::fflush(stderr);
  return 0;
}

int unknown_command(const char* name) {
  std::fprintf(stderr, "uwbnav: unknown command '%s'\n", name);
  usage(stderr);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || is_help(argv[1]) || (std::strcmp(argv[1], "help") == 0 && argc == 2)) {
    usage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  if (std::strcmp(argv[1], "help") == 0) {
    const uwbnav::cli::Command* c = find_command(argv[2]);
    return c == nullptr ? unknown_command(argv[2]) : command_help(*c, argc > 3 ? argv[3] : nullptr);
  }
  const uwbnav::cli::Command* c = find_command(argv[1]);
  if (c == nullptr) return unknown_command(argv[1]);
  for (int i = 2; i < argc; ++i) {
    if (is_help(argv[i])) return command_help(*c, argc > 2 ? argv[2] : nullptr);
  }
  return c->run(argc - 1, argv + 1);
}
