// Child process helpers for the HIL bench (see child_process.hpp).
#include "tools/hil/child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>

namespace uwbnav::hil {
namespace {

int decode_status(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

}  // namespace

Status spawn_self(const std::vector<std::string>& args, const std::string& log_path, int* pid, std::string* error) {
  int log_fd = -1;
  if (!log_path.empty()) {
    log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (log_fd < 0) {
      if (error) *error = "cannot open " + log_path + ": " + std::strerror(errno);
      return Status::kIoError;
    }
  }
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  std::fflush(nullptr);
  const pid_t child = ::fork();
  if (child < 0) {
    if (error) *error = std::string("fork: ") + std::strerror(errno);
    if (log_fd >= 0) ::close(log_fd);
    return Status::kIoError;
  }
  if (child == 0) {
    if (log_fd >= 0) {
      ::dup2(log_fd, STDOUT_FILENO);
      ::dup2(log_fd, STDERR_FILENO);
    }
    ::execv("/proc/self/exe", argv.data());
    _exit(127);
  }
  if (log_fd >= 0) ::close(log_fd);
  *pid = child;
  return Status::kOk;
}

bool child_running(int pid, int* exit_code) {
  int status = 0;
  const pid_t r = ::waitpid(pid, &status, WNOHANG);
  if (r == 0) return true;
  if (exit_code != nullptr) *exit_code = r == pid ? decode_status(status) : -1;
  return false;
}

int stop_child(int pid, int timeout_ms) {
  int code = -1;
  if (!child_running(pid, &code)) return code;
  ::kill(pid, SIGTERM);
  for (int waited_ms = 0; waited_ms < timeout_ms; waited_ms += 10) {
    if (!child_running(pid, &code)) return code;
    const timespec ts{0, 10 * 1000 * 1000};
    ::nanosleep(&ts, nullptr);
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  return ::waitpid(pid, &status, 0) == pid ? decode_status(status) : -1;
}

}  // namespace uwbnav::hil
