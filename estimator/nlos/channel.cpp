// Channel-diagnostics NLOS evidence (first-path vs received power).
#include "estimator/nlos/channel.hpp"

#include <cmath>

#include "estimator/types.hpp"

namespace uwbnav {

float channel_power_gap_db(float fp_power_dbm, float rx_power_dbm) {
  if (!std::isfinite(fp_power_dbm) || !std::isfinite(rx_power_dbm)) return kNaNf;
  return rx_power_dbm - fp_power_dbm;
}

float channel_p_nlos(float fp_power_dbm, float rx_power_dbm, float lo_db, float hi_db, float p_max) {
  const float gap_db = channel_power_gap_db(fp_power_dbm, rx_power_dbm);
  if (!std::isfinite(gap_db)) return kNaNf;
  if (gap_db <= lo_db || !(hi_db > lo_db)) return gap_db > hi_db ? p_max : 0.5F;
  if (gap_db >= hi_db) return p_max;
  return 0.5F + (p_max - 0.5F) * (gap_db - lo_db) / (hi_db - lo_db);
}

}  // namespace uwbnav
