// Helpers for the dataset tests: a scratch directory per test and file writers.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "tools/dataset/recording.hpp"

namespace uwbnav::dataset::testutil {

// Fresh empty directory named after the running test.
inline std::string scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::filesystem::path p = std::filesystem::path(::testing::TempDir()) / "uwbnav_dataset_tests" /
                            (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

inline void write_file(const std::string& path, const std::string& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr) << path;
  ASSERT_EQ(std::fwrite(bytes.data(), 1, bytes.size(), f), bytes.size());
  std::fclose(f);
}

inline std::string read_text(const std::string& path) {
  std::string s;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return s;
  char buf[4096];
  size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  std::fclose(f);
  return s;
}

inline const char* kAnchorsOk = "anchor_id,x_m,y_m,z_m\n1,0,0,2\n2,10,0,2\n3,10,10,2\n";

// True when some warning starts with `prefix` ("uwb.csv:4:") and contains `what`.
inline bool has_warning(const ReadReport& r, const std::string& prefix, const std::string& what) {
  return std::any_of(r.warnings.begin(), r.warnings.end(), [&](const std::string& w) {
    return w.rfind(prefix, 0) == 0 && w.find(what) != std::string::npos;
  });
}

inline std::string dump(const ReadReport& r) {
  std::string s = "error: " + r.error + "\n";
  for (const auto& w : r.warnings) s += w + "\n";
  return s;
}

}  // namespace uwbnav::dataset::testutil
