// Channel-diagnostics NLOS evidence: the difference between total received
// power and first-path power (DW1000 user manual §4.7, APS006 part 2: below
// about 6 dB the channel is likely LOS, above about 10 dB likely NLOS).
#pragma once

namespace uwbnav {

// rx - fp [dB]; NaN when either power is unknown (NaN).
float channel_power_gap_db(float fp_power_dbm, float rx_power_dbm);

// NLOS evidence from the power gap: 0.5 (neutral: no LOS evidence is claimed,
// a small gap is common under light NLOS) up to lo_db, rising linearly to
// p_max at hi_db and above. NaN when the diagnostics are absent.
float channel_p_nlos(float fp_power_dbm, float rx_power_dbm, float lo_db, float hi_db, float p_max);

}  // namespace uwbnav
