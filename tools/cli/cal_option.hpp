// `--cal FILE` of replay / run / firmware: loads a site range calibration file
// (docs/commissioning.md) into the site the board hands the firmware.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "tools/cli/args.hpp"
#include "tools/dataset/calibration.hpp"

namespace uwbnav::cli {

// No --cal: true, site untouched (uncalibrated unless the site says otherwise).
// With --cal: true when the file loaded and matches the site; else prints
// every problem as "who: file:line: reason" and returns false.
inline bool apply_cal_option(const Args& args, SiteConfig& site, const char* who) {
  if (!args.has("--cal")) return true;
  const std::string path = args.get("--cal");
  std::vector<std::string> errors;
  if (!ok(dataset::load_calibration(path, site, errors))) {
    for (const auto& e : errors) std::fprintf(stderr, "%s: %s\n", who, e.c_str());
    std::fprintf(stderr, "%s: calibration %s not loaded\n", who, path.c_str());
    return false;
  }
  std::printf("calibration: %s (%zu anchors x %zu tags, site sigma %.4f m)\n", path.c_str(), site.num_anchors,
              site.num_tags, static_cast<double>(site.range_offset_sigma_m));
  return true;
}

}  // namespace uwbnav::cli
