// `uwbnav sim SCENARIO --out DIR [--seed N]`: writes a simulated recording.
#include <cstdio>
#include <string>

#include "tools/cli/args.hpp"
#include "tools/dataset/recording.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::cli {

int cmd_sim(int argc, char** argv) {
  Args args(argc, argv, {"--list"});
  if (args.has("--list")) {
    for (const auto& n : sim::preset_names()) std::printf("%s\n", n.c_str());
    return 0;
  }
  uint64_t seed = 1;
  if (!args.error().empty() || args.positional().size() != 1 || !args.has("--out") ||
      !args.unknown({"--out", "--seed", "--list"}).empty() || !args.get_u64("--seed", 1, &seed)) {
    std::fprintf(stderr, "usage: uwbnav sim SCENARIO|FILE --out DIR [--seed N]   (uwbnav sim --list)\n");
    if (!args.error().empty()) std::fprintf(stderr, "uwbnav sim: %s\n", args.error().c_str());
    return 2;
  }
  dataset::Recording rec;
  std::string err;
  if (!ok(sim::simulate(args.positional()[0], seed, rec, &err))) {
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
