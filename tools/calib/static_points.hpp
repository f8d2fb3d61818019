// Static reference points for `uwbnav calibrate` (docs/commissioning.md
// "Static points"): time windows in which the vehicle stood still on a
// surveyed spot. Strict reader with file:line: reason errors.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "estimator/status.hpp"

namespace uwbnav::calib {

// One window: the body origin (the point truth.csv describes) stood at
// pos_nav_m with heading yaw_rad (when known) from t_start_us to t_end_us.
struct StaticPoint {
  std::string id;
  uint64_t t_start_us = 0;
  uint64_t t_end_us = 0;
  double pos_nav_m[3] = {0, 0, 0};
  bool has_yaw = false;
  double yaw_rad = 0.0;  // yaw of body x from nav x, CCW positive [rad]
  size_t line = 0;
};

// Columns: point_id,t_start_s,t_end_s,x_m,y_m,z_m,yaw_deg (yaw_deg may be empty).
// kOk, or kInvalidArgument / kNotFound with every problem in `errors`.
[[nodiscard]] Status read_static_points(const std::string& path, std::vector<StaticPoint>& out,
                                        std::vector<std::string>& errors);

// The same on text already in memory (`name` prefixes the messages).
[[nodiscard]] Status parse_static_points(const std::string& text, const std::string& name,
                                         std::vector<StaticPoint>& out, std::vector<std::string>& errors);

}  // namespace uwbnav::calib
