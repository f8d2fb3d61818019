// Runs this executable (`/proc/self/exe`) as a child process with other
// arguments (the HIL bench spawning `uwbnav firmware`) and stops it with SIGTERM.
#pragma once

#include <string>
#include <vector>

#include "estimator/status.hpp"

namespace uwbnav::hil {

// fork + execv("/proc/self/exe", args). args[0] is the program name shown in ps.
// log_path non-empty: the child's stdout and stderr go to that file.
// kOk: *pid set. kIoError: fork/open failed (`error` says why).
[[nodiscard]] Status spawn_self(const std::vector<std::string>& args, const std::string& log_path, int* pid,
                                std::string* error);

// True while the child runs; false once it exited (its status then in *exit_code:
// the exit status, or 128 + signal number).
bool child_running(int pid, int* exit_code);

// SIGTERM, wait up to timeout_ms, then SIGKILL. Returns the exit code as in
// child_running (-1 when the child could not be reaped).
int stop_child(int pid, int timeout_ms);

}  // namespace uwbnav::hil
