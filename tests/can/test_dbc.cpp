// docs/uwbnav.dbc is generated from the firmware message table
// (firmware/can/message_table.hpp): this test regenerates it in memory and fails
// when the committed file differs (UWBNAV_WRITE_DBC=1 rewrites the file), and
// checks the table itself and the run-time layout the codec derives from it.
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "firmware/can/e2e.hpp"
#include "firmware/can/messages.hpp"

namespace uwbnav::can {
namespace {

std::string num(double v) {
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed);  // DBC tools expect no exponents
  return std::string(buf, r.ptr);
}

std::string make_dbc() {
  std::ostringstream o;
  o << "VERSION \"uwbnav-can-1\"\n\n\n"
    << "NS_ :\n\tNS_DESC_\n\tCM_\n\tBA_DEF_\n\tBA_\n\tVAL_\n\tBA_DEF_DEF_\n\n"
    << "BS_:\n\n"
    << "BU_: UWBNAV HIL_RIG VEHICLE\n\n\n";
  for (size_t i = 0; i < kNumMessages; ++i) {
    const MessageDef& m = kMessages[i];
    const char* tx = m.from_uwbnav ? "UWBNAV" : "HIL_RIG";
    const char* rx = m.from_uwbnav ? "VEHICLE,HIL_RIG" : "UWBNAV";
    o << "BO_ " << m.id << ' ' << m.name << ": " << static_cast<int>(m.dlc) << ' ' << tx << '\n';
    for (uint8_t k = 0; k < m.num_signals; ++k) {
      const SignalDef& s = m.signals[k];
      o << " SG_ " << s.name << " : " << static_cast<int>(s.start_bit) << '|' << static_cast<int>(s.bit_len)
        << "@1" << (s.is_signed ? '-' : '+') << " (" << num(s.factor) << ',' << num(s.offset) << ") ["
        << num(s.non_finite == NonFinite::kRawZeroNa ? s.offset : s.min) << '|' << num(s.max) << "] \"" << s.unit
        << "\" " << rx << '\n';
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

}  // namespace
}  // namespace uwbnav::can
