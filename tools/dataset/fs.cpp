// File-system helpers for the host tools (see fs.hpp).
#include "tools/dataset/fs.hpp"

#include <sys/stat.h>

#include <cerrno>

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

}  // namespace uwbnav::dataset
