// Simulator scenarios: presets, file loading, duration override, recording
// metadata, parse errors, and that docs/simulator.md documents every key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tools/sim/rng.hpp"
#include "tools/sim/simulator.hpp"

namespace uwbnav::sim {
namespace {

TEST(SimScenario, DefaultPresetIsTheParkingLotWithNlos) {
  const std::vector<std::string> names = preset_names();
  ASSERT_FALSE(names.empty());
  EXPECT_EQ(names.front(), "parking_nlos");
  for (const char* n : {"parking_los", "seed000_protocol", "parking_outages", "indoor3d", "drive_1h"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  }
}

TEST(SimScenario, EveryPresetParsesSimulatesAndStaysInsideTheAnchorArea) {
  for (const std::string& name : preset_names()) {
    SimOptions opt;
    opt.seed = 1;
    SimOutput out;
    std::string err;
    ASSERT_EQ(simulate(name, opt, out, &err), Status::kOk) << name << ": " << err;
    EXPECT_EQ(out.rec.meta.at("name"), name);
    double lo[2] = {1e9, 1e9};
    double hi[2] = {-1e9, -1e9};
    for (size_t i = 0; i < out.rec.site.num_anchors; ++i) {
      const Vec3f& p = out.rec.site.anchors[i].pos_nav_m;
      lo[0] = std::min(lo[0], static_cast<double>(p.x));
      lo[1] = std::min(lo[1], static_cast<double>(p.y));
      hi[0] = std::max(hi[0], static_cast<double>(p.x));
      hi[1] = std::max(hi[1], static_cast<double>(p.y));
    }
    for (const TruthState& t : out.truth) {
      ASSERT_GT(t.pos_nav_m[0], lo[0]) << name << " leaves the site at t=" << t.t_us;
      ASSERT_LT(t.pos_nav_m[0], hi[0]) << name;
      ASSERT_GT(t.pos_nav_m[1], lo[1]) << name;
      ASSERT_LT(t.pos_nav_m[1], hi[1]) << name;
    }
    // Parked for at least 10 s at the start (levelling).
    for (size_t k = 0; k < 1000; ++k) {
      ASSERT_EQ(out.truth[k].vel_nav_mps[0], 0.0) << name;
      ASSERT_EQ(out.truth[k].vel_nav_mps[1], 0.0) << name;
    }
  }
}

TEST(SimScenario, RecordingCarriesMetaSiteAndFullRateTruth) {
  dataset::Recording rec;
  std::string err;
  ASSERT_EQ(simulate("parking_nlos", 123, rec, &err), Status::kOk) << err;
  EXPECT_EQ(rec.meta.at("source"), "uwbnav-sim");
  EXPECT_EQ(rec.meta.at("platform"), "ground");
  EXPECT_EQ(rec.meta.at("seed"), "123");
  EXPECT_EQ(rec.meta.at("imu_rate_hz"), "100");
  EXPECT_EQ(rec.meta.at("uwb_rate_hz"), "50");
  EXPECT_EQ(rec.meta.at("uwb_sigma_m"), "0.1");
  EXPECT_EQ(rec.meta.at("gravity_mps2"), "9.80665");
  EXPECT_EQ(std::strtof(rec.meta.at("gravity_mps2").c_str(), nullptr), rec.site.gravity_mps2);
  EXPECT_FALSE(rec.meta.at("description").empty());
  EXPECT_EQ(rec.site.num_anchors, 4U);
  EXPECT_EQ(rec.site.num_tags, 1U);
  EXPECT_TRUE(rec.site.has_imu);
  EXPECT_EQ(rec.imu.size(), 18000U);
  ASSERT_EQ(rec.truth.size(), rec.imu.size());
  for (size_t k = 0; k < rec.truth.size(); ++k) {
    ASSERT_EQ(rec.truth[k].t_us, rec.imu[k].t_us);
    ASSERT_TRUE(rec.truth[k].has_attitude);
  }
  // Roof tag above the anchors (seed 000 §2.1: anchors slightly lower than the vehicle).
  EXPECT_GT(rec.site.tags[0].lever_body_m.z, rec.site.anchors[0].pos_nav_m.z);
}

TEST(SimScenario, OneHourDriveHasTheExpectedSampleCounts) {
  dataset::Recording rec;
  std::string err;
  ASSERT_EQ(simulate("drive_1h", 1, rec, &err), Status::kOk) << err;
  EXPECT_EQ(rec.imu.size(), 360000U);
  EXPECT_NEAR(static_cast<double>(rec.uwb.size()), 180000.0 * 0.98, 700.0);
}

TEST(SimScenario, FileCanExtendAPresetAndOverrideTheDuration) {
  const std::string path = ::testing::TempDir() + "uwbnav_sim_ten_minutes.ini";
  {
    std::ofstream f(path);
    f << "# ten-minute variant of the one-hour drive\nbase = drive_1h\n[scenario]\nname = drive_10min\n"
         "duration_s = 600\n[uwb]\noutage = 100 110\n";
  }
  SimOptions opt;
  SimOutput out;
  std::string err;
  ASSERT_EQ(simulate(path, opt, out, &err), Status::kOk) << err;
  EXPECT_EQ(out.rec.imu.size(), 60000U);
  EXPECT_EQ(out.rec.meta.at("name"), "drive_10min");
  EXPECT_EQ(out.scenario.nlos.boxes.size(), 3U);  // inherited
  ASSERT_EQ(out.scenario.uwb.outages.size(), 1U);
  std::remove(path.c_str());
}

TEST(SimScenario, ImuCanBeDisabledForUwbOnlyRecordings) {
  Scenario sc;
  std::string err;
  ASSERT_EQ(parse_scenario("base = indoor3d\n[imu]\nenabled = 0\n", "t", sc, &err), Status::kOk) << err;
  SimOutput out;
  ASSERT_EQ(simulate_scenario(sc, SimOptions{}, out, &err), Status::kOk) << err;
  EXPECT_TRUE(out.rec.imu.empty());
  EXPECT_FALSE(out.rec.site.has_imu);
  EXPECT_FALSE(out.rec.truth.empty());
  EXPECT_FALSE(out.rec.uwb.empty());
}

struct BadCase {
  const char* text;
  const char* expect_in_error;
};

TEST(SimScenario, BadScenarioTextIsRejectedWithAOneLineErrorNamingTheLine) {
  const std::string site = "[site]\nanchor = 1 0 0 1\nanchor = 2 5 0 1\ntag = 0 0 0 1\n";
  const std::vector<BadCase> cases = {
      {"[nope]\n", ":1: unknown section"},
      {"[scenario\n", ":1: bad section header"},
      {"[scenario]\nfoo = 1\n", ":2: unknown key 'foo'"},
      {"[scenario]\nduration_s 10\n", ":2: expected 'key = value'"},
      {"[scenario]\nduration_s = ten\n", ":2: duration_s: not a finite number"},
      {"[scenario]\nduration_s = nan\n", ":2: duration_s: not a finite number"},
      {"[scenario]\nduration_s = -5\n", ":2: duration_s: value -5 outside"},
      {"[site]\nanchor = 1 0 0\n", ":2: anchor: anchor needs 'ID X Y Z'"},
      {"[site]\nanchor = -1 0 0 0\n", ":2: anchor: id must be an integer"},
      {"[uwb]\npacket_loss = 1.5\n", ":2: packet_loss: value 1.5 outside"},
      {"[uwb]\noutage = 10 5\n", ":2: outage: outage needs"},
      {"[nlos]\nbox = 0 0 0 1 1\n", ":2: box: expected 6 numbers"},
      {"[nlos]\nbox = 0 0 0 1 -1 1\n", ":2: box: box needs"},
      {"[nlos]\nbody_block = maybe\n", ":2: body_block: expected 0 or 1"},
      {"[route]\nmaneuver = fly 3 2\n", ":2: maneuver: unknown maneuver 'fly'"},
      {"[route]\nmaneuver = turn 90\n", ":2: maneuver: maneuver 'turn' needs 2"},
      {"[route]\nmaneuver = hold 0\n", ":2: maneuver: maneuver duration"},
      {"duration_s = 5\n", ":1: key 'duration_s' outside a section"},
      {"base = nowhere\n", ":1: unknown base preset 'nowhere'"},
      {"[scenario]\nname = x\nbase = indoor3d\n", ":3: unknown key 'base' in [scenario]"},
  };
  for (const BadCase& c : cases) {
    Scenario sc;
    std::string err;
    EXPECT_NE(parse_scenario(c.text, "bad.ini", sc, &err), Status::kOk) << c.text;
    EXPECT_NE(err.find(std::string("bad.ini") + c.expect_in_error), std::string::npos)
        << "text: " << c.text << "\nerror: " << err;
    EXPECT_EQ(err.find('\n'), std::string::npos) << err;
  }
  // Consistency errors found after parsing (texts prefixed with a valid site where noted).
  struct InvalidCase {
    bool with_site;
    const char* text;
    const char* expect_in_error;
  };
  const std::vector<InvalidCase> invalid = {
      {false, "[scenario]\n", "no anchor"},
      {false, "[site]\nanchor = 1 0 0 1\n", "no tag"},
      {false, "[site]\nanchor = 1 0 0 1\nanchor = 1 5 0 1\ntag = 0 0 0 1\n", "duplicate anchor id 1"},
      {true, "[imu]\nrate_hz = 3\n", "imu.rate_hz must divide"},
      {true, "[uwb]\nrate_hz = 7\n", "uwb.rate_hz must divide"},
      {true, "[route]\nloop_from = 3\nmaneuver = hold 1\n", "route.loop_from must index"},
  };
  for (const InvalidCase& c : invalid) {
    const std::string text = c.with_site ? site + c.text : std::string(c.text);
    Scenario sc;
    std::string err;
    EXPECT_NE(parse_scenario(text, "bad.ini", sc, &err), Status::kOk) << text;
    EXPECT_NE(err.find(c.expect_in_error), std::string::npos) << "text: " << text << "\nerror: " << err;
    EXPECT_EQ(err.find('\n'), std::string::npos) << err;
  }
}

TEST(SimScenario, MutatedPresetTextNeverCrashesTheParser) {
  // Deterministic mutations (own PRNG) of the default preset: replace, delete or
  // duplicate characters; the parser must answer kOk or a one-line error.
  const std::string base = preset_text("parking_nlos");
  Rng rng(2024);
  const std::string alphabet = "0123456789.-=[]# \nabcdefghijklmnopqrstuvwxyz_eE+";
  size_t rejected = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::string text = base;
    const int edits = 1 + static_cast<int>(rng.below(6));
    for (int e = 0; e < edits && !text.empty(); ++e) {
      const size_t pos = static_cast<size_t>(rng.below(text.size()));
      switch (rng.below(3)) {
        case 0: text[pos] = alphabet[static_cast<size_t>(rng.below(alphabet.size()))]; break;
        case 1: text.erase(pos, 1 + static_cast<size_t>(rng.below(20))); break;
        default: text.insert(pos, text.substr(pos, static_cast<size_t>(rng.below(30)))); break;
      }
    }
    Scenario sc;
    std::string err;
    if (!ok(parse_scenario(text, "mutated", sc, &err))) {
      ++rejected;
      EXPECT_FALSE(err.empty());
      EXPECT_EQ(err.find('\n'), std::string::npos) << err;
    }
  }
  EXPECT_GT(rejected, 50U);
}

TEST(SimScenario, MissingFileIsNotFoundNotACrash) {
  dataset::Recording rec;
  std::string err;
  EXPECT_EQ(simulate("/nonexistent/dir/scenario.ini", 0, rec, &err), Status::kNotFound);
  EXPECT_NE(err.find("neither a preset nor a readable scenario file"), std::string::npos) << err;
}

TEST(SimScenario, DocsDescribeEveryScenarioKeyAndPreset) {
  std::ifstream f(std::string(UWBNAV_SOURCE_DIR) + "/docs/simulator.md");
  ASSERT_TRUE(f) << "docs/simulator.md missing";
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string doc = ss.str();
  for (const std::string& key : scenario_keys()) {
    const size_t dot = key.find('.');
    const std::string section = "[" + key.substr(0, dot) + "]";
    const std::string name = "`" + key.substr(dot + 1) + "`";
    EXPECT_NE(doc.find(section), std::string::npos) << section;
    EXPECT_NE(doc.find(name), std::string::npos) << "docs/simulator.md does not document " << key;
  }
  for (const std::string& p : preset_names()) {
    EXPECT_NE(doc.find("`" + p + "`"), std::string::npos) << "preset " << p;
  }
}

}  // namespace
}  // namespace uwbnav::sim
