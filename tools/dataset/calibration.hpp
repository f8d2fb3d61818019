// Site range calibration file (docs/commissioning.md "Calibration file"): the
// per anchor/tag pair range offsets that `uwbnav calibrate` writes and the host
// boards load into SiteConfig at start-up. Strict reader: any malformed row,
// unknown or missing pair, NaN or duplicate is an error with file:line: reason,
// and nothing is applied. Host only (heap, files).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "estimator/status.hpp"
#include "estimator/types.hpp"

namespace uwbnav::dataset {

// First line of every calibration file (format version 1).
inline constexpr const char* kCalibrationMagic = "# uwbnav range calibration v1";

// One anchor/tag pair: measured minus true range [m] and its 1-sigma [m].
struct CalibrationPair {
  uint16_t anchor_id = 0;
  uint8_t tag_id = 0;
  float offset_m = 0.0F;
  float sigma_m = 0.0F;
  size_t line = 0;  // line in the file it was read from (0: not read from a file)
};

struct CalibrationFile {
  float site_sigma_m = kNaNf;      // 1-sigma the firmware assumes for every offset [m] (>= each pair's sigma_m)
  // 1-sigma of the range error the offsets leave on the commissioned lines of
  // sight (optional line; NaN: not given, the filter keeps uwb.survey_sigma) [m]
  float systematic_sigma_m = kNaNf;
  bool has_site_crc = false;       // site_crc32 line present
  uint32_t site_crc32 = 0;         // site_crc32() of the survey the offsets were made for
  size_t site_crc_line = 0;
  std::vector<std::string> info;   // other "key = value" lines, kept verbatim (method, source, ...)
  std::vector<CalibrationPair> pairs;
};

// CRC-32 over the anchor ids and positions and the tag ids and lever arms (as
// float bits, in table order): a calibration made for one survey refuses to
// load on a re-surveyed or different site.
uint32_t site_crc32(const SiteConfig& site);

// Parses `text` (the file's content; `name` prefixes messages). Checks the
// format only. kOk or kInvalidArgument with every problem in `errors`
// ("name:line: reason", at most kMaxErrors).
[[nodiscard]] Status parse_calibration(const std::string& text, const std::string& name, CalibrationFile& out,
                                       std::vector<std::string>& errors);

// Checks a parsed file against the site: every pair's anchor and tag exist,
// every anchor/tag pair of the site is present exactly once, site_crc32 (when
// given) matches. Messages name the line of the offending row.
[[nodiscard]] Status check_calibration(const CalibrationFile& cal, const SiteConfig& site, const std::string& name,
                                       std::vector<std::string>& errors);

// Fills site.range_offset_m / range_offset_sigma_m / range_systematic_sigma_m from a checked file.
void apply_calibration(const CalibrationFile& cal, SiteConfig& site);

// read_file + parse + check + apply. On failure `site` is left unchanged.
[[nodiscard]] Status load_calibration(const std::string& path, SiteConfig& site, std::vector<std::string>& errors);

// Writes the file (creating or replacing `path`): magic line, site_sigma_m,
// systematic_sigma_m (when set), site_crc32 (when set), the `info` lines, then
// the pair table.
[[nodiscard]] Status write_calibration(const std::string& path, const CalibrationFile& cal);

// Text of a calibration file (what write_calibration writes).
std::string format_calibration(const CalibrationFile& cal);

inline constexpr size_t kMaxCalibrationErrors = 50;

}  // namespace uwbnav::dataset
