// Small file-system helpers for the host tools.
#pragma once

#include <string>

namespace uwbnav::dataset {

// Creates `dir` and its missing parents (mkdir -p). False when one cannot be created.
bool make_dirs(const std::string& dir);

}  // namespace uwbnav::dataset
