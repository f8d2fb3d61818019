// Small file-system helpers for the host tools.
#pragma once

#include <string>

namespace uwbnav::dataset {

// Creates `dir` and its missing parents (mkdir -p). False when one cannot be created.
bool make_dirs(const std::string& dir);

// An output directory a command creates for its results: create() makes it
// (mkdir -p) and remembers the outermost directory that did not exist before;
// unless keep() is called, the destructor removes that directory with whatever
// the command wrote into it, so a failed command leaves no (empty or partial)
// output directory behind. Directories that existed before are never removed.
class OutputDir {
 public:
  OutputDir() = default;
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;
  bool create(const std::string& dir);
  void keep() { created_.clear(); }

 private:
  std::string created_;  // outermost directory created by create(); empty: nothing to undo
};

}  // namespace uwbnav::dataset
