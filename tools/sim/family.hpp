// Randomized Monte-Carlo scenario family (docs/simulator.md "Scenario family"):
// named cells, each drawing a complete random Scenario from a seed with the
// project's own generator, so `family:CELL:SEED` names one reproducible drive.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::sim {

// Seed sets (docs/evaluation.md): develop and tune on the tuning seeds only,
// report on the reporting seeds.
constexpr uint64_t kTuningSeedFirst = 1;
constexpr uint64_t kTuningSeedLast = 99;
constexpr uint64_t kReportingSeedFirst = 1000;
constexpr uint64_t kReportingSeedLast = 1999;

struct FamilyCell {
  std::string name;
  std::string description;
};

// The cells in table order.
const std::vector<FamilyCell>& family_cells();

struct FamilyOptions {
  bool fast = false;  // short drives (CI subset): at most 60 s, ground_blocked 150 s, outage 100 s
};

// Draws the scenario of drive CELL:SEED. kNotFound (and `error`) for an unknown cell.
[[nodiscard]] Status draw_family_scenario(const std::string& cell, uint64_t seed, const FamilyOptions& options,
                                          Scenario& out, std::string* error);

// Draws and simulates drive CELL:SEED; the recording's meta.ini names it (`sim_family`).
[[nodiscard]] Status simulate_family(const std::string& cell, uint64_t seed, const FamilyOptions& options,
                                     SimOutput& out, std::string* error);

// Splits "family:CELL:SEED"; false when `spec` is not of that form.
bool parse_family_spec(const std::string& spec, std::string& cell, uint64_t& seed);

}  // namespace uwbnav::sim
