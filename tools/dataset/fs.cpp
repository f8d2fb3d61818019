// File-system helpers for the host tools (see fs.hpp).
#include "tools/dataset/fs.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <filesystem>
#include <system_error>

namespace uwbnav::dataset {

bool make_dirs(const std::string& dir) {
  std::string path;
  for (size_t i = 0; i <= dir.size(); ++i) {
    if (i == dir.size() || dir[i] == '/') {
      if (!path.empty() && ::mkdir(path.c_str(), 0755) != 0 && errno != EEXIST) return false;
    }
    if (i < dir.size()) path += dir[i];
  }
  return true;
}

OutputDir::~OutputDir() {
  if (created_.empty()) return;
  std::error_code ec;
  std::filesystem::remove_all(created_, ec);  // best effort: nothing to report to on the way out
}

bool OutputDir::create(const std::string& dir) {
  std::string path;
  for (size_t i = 0; i <= dir.size(); ++i) {
    if (i == dir.size() || dir[i] == '/') {
      if (!path.empty()) {
        if (::mkdir(path.c_str(), 0755) == 0) {
          if (created_.empty()) created_ = path;
        } else if (errno != EEXIST) {
          return false;
        }
      }
    }
    if (i < dir.size()) path += dir[i];
  }
  struct stat st {};
  return ::stat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

}  // namespace uwbnav::dataset
