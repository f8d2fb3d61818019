// Column lists of every format v1 table (docs/dataset-format.md), shared by
// the readers and the writers so both always agree with the spec.
#pragma once

#include "tools/dataset/csv.hpp"

namespace uwbnav::dataset::tables {

inline const csv::Columns kAnchors{{"anchor_id", "x_m", "y_m", "z_m"}, {}};
inline const csv::Columns kTags{{"tag_id", "x_m", "y_m", "z_m"}, {}};
inline const csv::Columns kUwb{{"t_s", "anchor_id", "range_m"},
                               {"tag_id", "nlos", "fp_power_dbm", "rx_power_dbm"}};
inline const csv::Columns kImu{
    {"t_s", "ax_mps2", "ay_mps2", "az_mps2", "gx_radps", "gy_radps", "gz_radps"}, {}};
inline const csv::Columns kTruth{{"t_s", "x_m", "y_m", "z_m"}, {"qw", "qx", "qy", "qz"}, true};
// gnss.csv: an extension of format v1 (docs/dataset-format.md "gnss.csv"); older readers ignore the file.
inline const csv::Columns kGnss{{"t_s", "x_m", "y_m", "z_m", "sx_m", "sy_m", "sz_m"},
                                {"fix", "num_sv", "latency_s", "vx_mps", "vy_mps", "vz_mps", "sv_mps"}};
// neighbours.csv: an extension of format v1 (docs/dataset-format.md "neighbours.csv"); older readers ignore the file.
inline const csv::Columns kNeighbours{
    {"t_s", "vehicle_id", "x_m", "y_m", "z_m", "pxx_m2", "pxy_m2", "pxz_m2", "pyy_m2", "pyz_m2", "pzz_m2"},
    {"latency_s", "vx_mps", "vy_mps", "vz_mps", "coop"}};
inline const csv::Columns kEstimates{{"t_s", "x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps", "qw",
                                      "qx", "qy", "qz", "sx_m", "sy_m", "sz_m", "status"},
                                     {}};
inline const csv::Columns kRanges{{"t_s", "anchor_id", "tag_id", "range_m", "innovation_m", "p_svm",
                                   "p_mc", "p_fused", "nlos", "used"},
                                  {}};

}  // namespace uwbnav::dataset::tables
