// `uwbnav sim SCENARIO --out DIR [--seed N]` and `uwbnav sim family:CELL:SEED --out DIR`:
// writes a simulated recording.
#include <cstdio>
#include <string>
#include <utility>

#include "tools/cli/args.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/sim/family.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::cli {

int cmd_sim(int argc, char** argv) {
  Args args(argc, argv, {"--list"});
  if (args.has("--list")) {
    for (const auto& n : sim::preset_names()) std::printf("%s\n", n.c_str());
    std::printf("\nfamily cells (family:CELL:SEED; tuning seeds 1-99, reporting seeds 1000-1999):\n");
    for (const auto& c : sim::family_cells()) std::printf("family:%-16s %s\n", c.name.c_str(), c.description.c_str());
    return 0;
  }
  uint64_t seed = 1;
  if (!args.error().empty() || args.positional().size() != 1 || !args.has("--out") ||
      !args.unknown({"--out", "--seed", "--list"}).empty() || !args.get_u64("--seed", 1, &seed)) {
    std::fprintf(stderr, "usage: uwbnav sim SCENARIO|FILE --out DIR [--seed N]   (uwbnav sim --list)\n"
                         "       uwbnav sim family:CELL:SEED --out DIR\n");
    if (!args.error().empty()) std::fprintf(stderr, "uwbnav sim: %s\n", args.error().c_str());
    return 2;
  }
  dataset::Recording rec;
  std::string err;
  std::string cell;
  uint64_t family_seed = 0;
  if (sim::parse_family_spec(args.positional()[0], cell, family_seed)) {
    if (args.has("--seed")) {
      std::fprintf(stderr, "uwbnav sim: a family drive carries its seed (family:CELL:SEED); drop --seed\n");
      return 2;
    }
    sim::SimOutput so;
    if (!ok(sim::simulate_family(cell, family_seed, sim::FamilyOptions{}, so, &err))) {
      std::fprintf(stderr, "uwbnav sim: %s\n", err.c_str());
      return 1;
    }
    rec = std::move(so.rec);
    seed = family_seed;
  } else if (!ok(sim::simulate(args.positional()[0], seed, rec, &err))) {
    std::fprintf(stderr, "uwbnav sim: %s\n", err.c_str());
    return 1;
  }
  const std::string out = args.get("--out");
  if (!ok(dataset::write_recording(out, rec))) {
    std::fprintf(stderr, "uwbnav sim: cannot write recording to %s\n", out.c_str());
    return 1;
  }
  std::printf("sim: %s seed %llu -> %s (%zu IMU samples, %zu ranges, %.1f s)\n", rec.name().c_str(),
              static_cast<unsigned long long>(seed), out.c_str(), rec.imu.size(), rec.uwb.size(),
              rec.truth.empty() ? 0.0 : static_cast<double>(rec.truth.back().t_us - rec.truth.front().t_us) * 1e-6);
  return 0;
}

}  // namespace uwbnav::cli
