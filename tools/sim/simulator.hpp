// Deterministic UWB/IMU scenario simulator: produces a format v1 Recording
// (truth, IMU, ranges with NLOS labels) from a scenario preset or file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "tools/dataset/recording.hpp"

namespace uwbnav::sim {

// Names of the built-in scenarios; the first is the default of the main job.
std::vector<std::string> preset_names();

// Runs a built-in preset (by name) or a scenario file (by path). Same seed ->
// bit-identical recording. `error` receives a one-line reason on failure.
[[nodiscard]] Status simulate(const std::string& scenario, uint64_t seed, dataset::Recording& out,
                              std::string* error);

}  // namespace uwbnav::sim
