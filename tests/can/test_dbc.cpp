// docs/uwbnav.dbc is generated from the firmware message table
// (firmware/can/message_table.hpp): this test regenerates it in memory and fails
// when the committed file differs (UWBNAV_WRITE_DBC=1 rewrites the file), and
// checks the table itself and the run-time layout the codec derives from it.
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "firmware/can/e2e.hpp"
#include "firmware/can/messages.hpp"

namespace uwbnav::can {
namespace {

std::string num(double v) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed);  // DBC tools expect no exponents
  return std::string(buf, r.ptr);
}

// The DBC range includes a "not available" code: raw 0 (kRawZeroNa) or the
// field minimum (kRawMinNa), which lie outside the clipping range [min, max].
double dbc_min(const SignalDef& s) {
  if (s.non_finite == NonFinite::kRawZeroNa) return s.offset;
#if UWBNAV_COOP
  if (s.non_finite == NonFinite::kRawMinNa) return -std::ldexp(1.0, s.bit_len - 1) * s.factor + s.offset;
#endif
  return s.min;
}

std::string make_dbc() {
  std::ostringstream o;
  o << "VERSION \"uwbnav-can-1\"\n\n\n"
    << "NS_ :\n\tNS_DESC_\n\tCM_\n\tBA_DEF_\n\tBA_\n\tVAL_\n\tBA_DEF_DEF_\n\n"
    << "BS_:\n\n"
    << "BU_: UWBNAV HIL_RIG VEHICLE" << (UWBNAV_COOP ? " V2X_GW" : "") << (UWBNAV_GNSS ? " GNSS_GW" : "")
    << "\n\n\n";
  for (size_t i = 0; i < kNumMessages; ++i) {
    const MessageDef& m = kMessages[i];
    o << "BO_ " << m.id << ' ' << m.name << ": " << static_cast<int>(m.dlc) << ' ' << m.transmitter << '\n';
    for (uint8_t k = 0; k < m.num_signals; ++k) {
      const SignalDef& s = m.signals[k];
      o << " SG_ " << s.name << " : " << static_cast<int>(s.start_bit) << '|' << static_cast<int>(s.bit_len)
        << "@1" << (s.is_signed ? '-' : '+') << " (" << num(s.factor) << ',' << num(s.offset) << ") ["
        << num(dbc_min(s)) << '|' << num(s.max) << "] \"" << s.unit << "\" " << m.receivers << '\n';
    }
    o << '\n';
  }
  o << '\n';
  o << "CM_ \"uwbnav CAN interface (docs/can.md). GENERATED from firmware/can/message_table.hpp by "
       "tests/can/test_dbc.cpp - do not edit; regenerate with UWBNAV_WRITE_DBC=1 uwbnav_tests_can "
       "--gtest_filter=CanDbc.*. Every frame: byte 0 = CRC-8 SAE J1850 (poly 0x1D, init 0xFF, xor 0xFF) over "
       "E2EDataID low byte, E2EDataID high byte, bytes 1..7; byte 1 bits 0..3 = alive counter 0..14.\";\n";
  o << "CM_ BU_ UWBNAV \"uwbnav positioning ECU (IMU + UWB fusion)\";\n";
  o << "CM_ BU_ HIL_RIG \"hardware-in-the-loop rig injecting sensor frames\";\n";
  o << "CM_ BU_ VEHICLE \"vehicle network consumers of the position\";\n";
#if UWBNAV_COOP
  o << "CM_ BU_ V2X_GW \"V2X / UWB-data gateway: forwards UWBNAV_Coop* to other vehicles and relays their states as "
       "V2X_Neighbour* (cooperative positioning)\";\n";
#endif
#if UWBNAV_GNSS
  o << "CM_ BU_ GNSS_GW \"GNSS receiver or its gateway: sends the receiver's fixes, already in the navigation frame, as "
       "GNSS_Fix*\";\n";
#endif
  for (size_t i = 0; i < kNumMessages; ++i) {
    const MessageDef& m = kMessages[i];
    o << "CM_ BO_ " << m.id << " \"" << m.comment << "\";\n";
    for (uint8_t k = 0; k < m.num_signals; ++k) {
      o << "CM_ SG_ " << m.id << ' ' << m.signals[k].name << " \"" << m.signals[k].comment << "\";\n";
    }
  }
  o << "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n";
  o << "BA_DEF_ BO_ \"GenMsgSendType\" ENUM \"Cyclic\",\"Event\";\n";
  o << "BA_DEF_ BO_ \"E2EDataID\" INT 0 65535;\n";
  o << "BA_DEF_ \"BusType\" STRING ;\n";
  o << "BA_DEF_DEF_ \"GenMsgCycleTime\" 0;\n";
  o << "BA_DEF_DEF_ \"GenMsgSendType\" \"Cyclic\";\n";
  o << "BA_DEF_DEF_ \"E2EDataID\" 0;\n";
  o << "BA_DEF_DEF_ \"BusType\" \"CAN\";\n";
  o << "BA_ \"BusType\" \"CAN\";\n";
  for (size_t i = 0; i < kNumMessages; ++i) {
    const MessageDef& m = kMessages[i];
    o << "BA_ \"GenMsgCycleTime\" BO_ " << m.id << ' ' << m.cycle_ms << ";\n";
    o << "BA_ \"GenMsgSendType\" BO_ " << m.id << ' ' << (m.cycle_ms > 0 ? 0 : 1) << ";\n";
    o << "BA_ \"E2EDataID\" BO_ " << m.id << ' ' << m.data_id << ";\n";
  }
  for (size_t i = 0; i < kNumMessages; ++i) {
    const MessageDef& m = kMessages[i];
    for (uint8_t k = 0; k < m.num_signals; ++k) {
      const SignalDef& s = m.signals[k];
      if (s.values == nullptr) continue;
      o << "VAL_ " << m.id << ' ' << s.name;
      for (int v = s.num_values - 1; v >= 0; --v) o << ' ' << s.values[v].value << " \"" << s.values[v].name << '"';
      o << " ;\n";
    }
  }
  return o.str();
}

const std::string kDbcPath = std::string(UWBNAV_SOURCE_DIR) + "/docs/uwbnav.dbc";

TEST(CanDbc, CommittedDbcMatchesTheFirmwareMessageTable) {
#if !UWBNAV_COOP
  GTEST_SKIP() << "docs/uwbnav.dbc describes the full message set (UWBNAV_COOP=1)";
#endif
  const std::string generated = make_dbc();
  if (const char* w = std::getenv("UWBNAV_WRITE_DBC"); w != nullptr && std::string(w) == "1") {
    std::ofstream(kDbcPath, std::ios::binary) << generated;
  }
  std::ifstream in(kDbcPath, std::ios::binary);
  ASSERT_TRUE(in.good()) << "missing " << kDbcPath;
  std::stringstream committed;
  committed << in.rdbuf();
  EXPECT_EQ(committed.str(), generated)
      << "docs/uwbnav.dbc is stale: regenerate with UWBNAV_WRITE_DBC=1 uwbnav_tests_can --gtest_filter=CanDbc.*";
}

TEST(CanDbc, SignalsFitTheFrameAndNeverOverlap) {
  for (size_t i = 0; i < kNumMessages; ++i) {
    const MessageDef& m = kMessages[i];
    uint64_t used = 0;
    for (uint8_t k = 0; k < m.num_signals; ++k) {
      const SignalDef& s = m.signals[k];
      ASSERT_LE(s.start_bit + s.bit_len, m.dlc * 8) << m.name << '.' << s.name;
      for (unsigned b = s.start_bit; b < unsigned{s.start_bit} + s.bit_len; ++b) {
        EXPECT_EQ(used & (uint64_t{1} << b), 0U) << m.name << '.' << s.name << " overlaps at bit " << b;
        used |= uint64_t{1} << b;
      }
      // Physical limits must be representable in the raw field.
      const double raw_lo = (s.min - s.offset) / s.factor;
      const double raw_hi = (s.max - s.offset) / s.factor;
      const double field_lo = s.is_signed ? -std::ldexp(1.0, s.bit_len - 1) : 0.0;
      const double field_hi = s.is_signed ? std::ldexp(1.0, s.bit_len - 1) - 1.0 : std::ldexp(1.0, s.bit_len) - 1.0;
      EXPECT_GE(std::round(raw_lo), field_lo) << m.name << '.' << s.name;
      EXPECT_LE(std::round(raw_hi), field_hi) << m.name << '.' << s.name;
    }
  }
}

TEST(CanDbc, RuntimeLayoutIsTheTableWithRawLimitsEqualToLlroundOfThePhysicalLimits) {
  for (size_t i = 0; i < kNumMessages; ++i) {
    const MessageDef& m = kMessages[i];
    const MessageLayout* l = find_layout(m.id);
    ASSERT_NE(l, nullptr) << m.name;
    EXPECT_EQ(l, &layout_of(static_cast<MsgId>(m.id)));
    EXPECT_EQ(l->data_id, m.data_id);
    EXPECT_EQ(l->dlc, m.dlc);
    ASSERT_EQ(l->num_payload + kFirstPayloadSignal, m.num_signals) << m.name;
    for (uint8_t k = kFirstPayloadSignal; k < m.num_signals; ++k) {
      const SignalDef& d = m.signals[k];
      const SignalLayout& s = signal_layout(*l, k);
      EXPECT_EQ(s.start_bit, d.start_bit) << m.name << '.' << d.name;
      EXPECT_EQ(s.bit_len, d.bit_len) << m.name << '.' << d.name;
      EXPECT_EQ(s.is_signed, d.is_signed) << m.name << '.' << d.name;
      EXPECT_EQ(s.non_finite, d.non_finite) << m.name << '.' << d.name;
      EXPECT_EQ(1.0 / s.inv_factor, d.factor) << m.name << '.' << d.name;
      EXPECT_EQ(-static_cast<double>(s.raw_zero) / s.inv_factor, d.offset) << m.name << '.' << d.name;
      const int64_t raw_min = std::llround((d.min - d.offset) / d.factor);
      const int64_t raw_max = std::llround((d.max - d.offset) / d.factor);
      bool flagged = false;
      if (d.factor == 1.0 && d.offset == 0.0 && d.min == 0.0 && !d.is_signed) {
        // Count signal: clips at the field maximum, which must be the table's max.
        EXPECT_EQ(raw_from_count(s, ~uint64_t{0}, &flagged), raw_max) << m.name << '.' << d.name;
        EXPECT_TRUE(flagged);
        EXPECT_EQ(raw_min, 0);
      } else {
        EXPECT_EQ(s.raw_min, raw_min) << m.name << '.' << d.name;
        EXPECT_EQ(s.raw_max, raw_max) << m.name << '.' << d.name;
      }
    }
  }
  EXPECT_EQ(find_layout(0x7FF), nullptr);
  for (const double v : {0.5, -0.5, 1.5, -1.5, 2.4999999999999996, 0.49999999999999994, -0.49999999999999994,
                         32767.0, -32768.0, 65535.5, 1e15 + 0.5}) {
    EXPECT_EQ(round_half_away(v), std::llround(v)) << v;
  }
}

TEST(CanDbc, EveryMessageHasTheE2eHeaderAndUniqueIdsAndDataIds) {
  for (size_t i = 0; i < kNumMessages; ++i) {
    const MessageDef& m = kMessages[i];
    ASSERT_GE(m.num_signals, 3);
    EXPECT_EQ(m.signals[kSigCrc].start_bit, 0);
    EXPECT_EQ(m.signals[kSigCrc].bit_len, 8);
    EXPECT_EQ(m.signals[kSigCounter].start_bit, 8);
    EXPECT_EQ(m.signals[kSigCounter].bit_len, 4);
    EXPECT_EQ(m.signals[kSigSaturated].start_bit, 15);
    EXPECT_LE(m.id, 0x7FFU) << "11-bit identifiers only";
    EXPECT_EQ(m.dlc, 8);
    for (size_t j = i + 1; j < kNumMessages; ++j) {
      EXPECT_NE(m.id, kMessages[j].id);
      EXPECT_NE(m.data_id, kMessages[j].data_id);
    }
  }
}

// The codec against the DBC as a tool nobody here wrote reads it: canmatrix
// (tests/scripts/dbc_decode_frames.py, /usr/bin/python3) decodes frames the
// C++ side produced, and raw and physical values must agree signal by signal:
// random payloads of every message (raw bits, scaling, sign, "not available"
// codes) and, for the cooperative groups, frames encode_coop() made from known
// states (physical value within half a DBC step of the state).
TEST(CanDbc, CanmatrixDecodesTheCodecFramesAsTheFirmwareDoes) {
  const std::string dir = std::string(UWBNAV_BINARY_DIR) + "/tests/dbc_canmatrix";
  std::filesystem::create_directories(dir);
  struct Expect {
    size_t frame;
    std::string signal;
    int64_t raw;
    double phys;     // NaN: a "not available" code
    double within;   // tolerance of phys
  };
  std::vector<hal::CanFrame> frames;
  std::vector<Expect> expect;
  std::mt19937 rng(1601);
  std::uniform_int_distribution<int> byte(0, 255);
  for (const MessageDef& m : kMessages) {
    const MessageLayout& l = *find_layout(m.id);
    for (int i = 0; i < 50; ++i) {
      hal::CanFrame f;
      f.id = m.id;
      f.len = 8;
      for (uint8_t b = 0; b < 8; ++b) f.data[b] = static_cast<uint8_t>(byte(rng));
      if (i == 0) std::fill(f.data, f.data + 8, uint8_t{0});
      if (i == 1) std::fill(f.data, f.data + 8, uint8_t{0xFF});
      for (uint8_t k = 0; k < m.num_signals; ++k) {
        const SignalDef& d = m.signals[k];
        if (k < kFirstPayloadSignal || (d.factor == 1.0 && d.offset == 0.0 && d.min == 0.0 && !d.is_signed)) {
          const auto raw = static_cast<int64_t>(get_bits(f.data, d.start_bit, d.bit_len));
          expect.push_back({frames.size(), d.name, raw, static_cast<double>(raw), 0.0});
          continue;
        }
        const SignalLayout& sl = signal_layout(l, k);
        const int64_t raw = read_raw(sl, f.data);
        const float phys = phys_from_raw(sl, raw);
        // The firmware's float is the one nearest to the exact value.
        const float ulp = std::nextafter(std::fabs(phys), std::numeric_limits<float>::infinity()) - std::fabs(phys);
        const double half_ulp = std::isnan(phys) ? 0.0 : 0.5 * static_cast<double>(ulp);
        expect.push_back({frames.size(), d.name, raw, static_cast<double>(phys), half_ulp + 1e-12});
      }
      frames.push_back(f);
    }
  }
#if UWBNAV_COOP
  std::uniform_real_distribution<float> horiz(-2.1e6F, 2.1e6F), vert(-16000.0F, 16000.0F), vel(-300.0F, 300.0F),
      sig(0.001F, 60.0F), rho(-0.9F, 0.9F);
  for (int i = 0; i < 40; ++i) {
    NeighbourState s;
    s.t_us = 0x1234567890ULL + static_cast<uint64_t>(i) * 100000;
    s.vehicle_id = static_cast<uint16_t>(0x8001 + i);
    s.pos_nav_m = Vec3f{i % 2 == 0 ? horiz(rng) : 0.001F * static_cast<float>(i), horiz(rng), vert(rng)};
    s.vel_nav_mps = Vec3f{vel(rng), i % 4 == 0 ? kNaNf : vel(rng), vel(rng)};
    const Vec3f sd{sig(rng), sig(rng), sig(rng)};
    const float r[3] = {rho(rng), rho(rng), rho(rng)};
    s.cov_pos_m2[0] = sd.x * sd.x;
    s.cov_pos_m2[1] = r[0] * sd.x * sd.y;
    s.cov_pos_m2[2] = r[1] * sd.x * sd.z;
    s.cov_pos_m2[3] = sd.y * sd.y;
    s.cov_pos_m2[4] = r[2] * sd.y * sd.z;
    s.cov_pos_m2[5] = sd.z * sd.z;
    s.cooperative = i % 3 == 0;
    const CoopGroup g = i % 2 == 0 ? CoopGroup::kOwn : CoopGroup::kNeighbour;
    const char* p = g == CoopGroup::kOwn ? "Coop_" : "Neighbour_";
    hal::CanFrame f[kCoopFrames];
    ASSERT_FALSE(encode_coop(s, g, static_cast<uint8_t>(i % 15), f));
    const size_t first = frames.size();
    for (const auto& fr : f) frames.push_back(fr);
    auto want = [&](size_t part, const char* name, double value, double step) {
      expect.push_back({first + part, std::string(p) + name, 0, value, std::isnan(value) ? 0.0 : step / 2.0 + 1e-9});
      expect.back().raw = std::numeric_limits<int64_t>::min();  // not compared
    };
    want(0, "VehicleId", s.vehicle_id, 0.0);
    want(0, "TimeUs", static_cast<double>(s.t_us & 0xFFFFFFFFU), 0.0);
    want(0, "Cooperative", s.cooperative ? 1.0 : 0.0, 0.0);
    want(0, "Valid", 1.0, 0.0);
    const double ulp_x = std::fabs(static_cast<double>(s.pos_nav_m.x)) * 0x1p-23;
    want(1, "PosX", static_cast<double>(s.pos_nav_m.x), 0.001 + ulp_x);
    want(2, "PosY", static_cast<double>(s.pos_nav_m.y), 0.001);
    want(3, "PosZ", static_cast<double>(s.pos_nav_m.z), 0.001);
    want(1, "VelX", static_cast<double>(s.vel_nav_mps.x), 0.01);
    want(2, "VelY", static_cast<double>(s.vel_nav_mps.y), 0.01);
    want(3, "VelZ", static_cast<double>(s.vel_nav_mps.z), 0.01);
    want(4, "SigmaX", std::sqrt(static_cast<double>(s.cov_pos_m2[0])), 0.001 + 1e-6);
    want(4, "SigmaZ", std::sqrt(static_cast<double>(s.cov_pos_m2[5])), 0.001 + 1e-6);
    want(5, "CorrXY", static_cast<double>(r[0]), 1.0 / 127.0 + 1e-6);
    want(5, "CorrYZ", static_cast<double>(r[2]), 1.0 / 127.0 + 1e-6);
  }
#endif
  {
    std::ofstream in(dir + "/frames.txt");
    char buf[40];
    for (const auto& f : frames) {
      std::snprintf(buf, sizeof buf, "%03X ", f.id);
      in << buf;
      for (uint8_t b = 0; b < f.len; ++b) {
        std::snprintf(buf, sizeof buf, "%02X", f.data[b]);
        in << buf;
      }
      in << '\n';
    }
  }
  if (!std::filesystem::exists("/usr/bin/python3")) GTEST_SKIP() << "/usr/bin/python3 not found";
  const std::string cmd = "/usr/bin/python3 " + std::string(UWBNAV_SOURCE_DIR) + "/tests/scripts/dbc_decode_frames.py " +
                          kDbcPath + ' ' + dir + "/frames.txt " + dir + "/decoded.txt > " + dir + "/log.txt 2>&1";
  const int rc = std::system(cmd.c_str());
  if (WIFEXITED(rc) && WEXITSTATUS(rc) == 3) GTEST_SKIP() << "python3-canmatrix not installed";
  ASSERT_EQ(rc, 0) << cmd << " (see " << dir << "/log.txt)";
  struct Got {
    int64_t raw;
    double phys;
    std::string named;
  };
  std::map<std::pair<size_t, std::string>, Got> got;
  std::ifstream out(dir + "/decoded.txt");
  size_t index = 0;
  std::string name, phys, named;
  int64_t raw = 0;
  while (out >> index >> name >> raw >> phys >> named) got[{index, name}] = Got{raw, std::stod(phys), named};
  size_t compared = 0;
  for (const Expect& e : expect) {
    const auto it = got.find({e.frame, e.signal});
    ASSERT_NE(it, got.end()) << "canmatrix did not decode " << e.signal << " of frame " << e.frame;
    const Got& g = it->second;
    if (e.raw != std::numeric_limits<int64_t>::min()) {
      EXPECT_EQ(g.raw, e.raw) << e.signal << " frame " << e.frame;
    }
    if (std::isnan(e.phys)) {
      EXPECT_TRUE(g.named == "not_reported" || g.named == "not_available")
          << e.signal << " raw " << g.raw << ": the firmware's not-available code is not named in the DBC";
    } else {
      EXPECT_NEAR(g.phys, e.phys, e.within) << e.signal << " frame " << e.frame;
    }
    ++compared;
  }
  EXPECT_EQ(got.size(), [&] {
    size_t n = 0;
    for (const auto& f : frames) n += find_message(f.id)->num_signals;
    return n;
  }()) << "every signal of every frame decoded";
  EXPECT_GT(compared, 3000U);
}

}  // namespace
}  // namespace uwbnav::can
