// libFuzzer target: the format v1 recording reader, one file type per input.
// First byte selects the file the rest of the input becomes (anchors, tags,
// uwb, imu, truth, meta.ini, uwb.csv.gz, site calibration text, gnss.csv,
// neighbours.csv); the other files of the recording are fixed and valid. A read
// that succeeds must hold only finite, time-ordered rows within the table
// capacities, GNSS fixes with positive sigmas and neighbour states of vehicle ids
// with positive definite covariances, arriving no earlier than their validity,
// in arrival order.
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "tools/dataset/calibration.hpp"
#include "tools/dataset/recording.hpp"

namespace {

const std::string& scratch() {
  static const std::string dir = [] {
    const char* base = std::getenv("TMPDIR");
    std::string d = std::string(base != nullptr ? base : "/tmp") + "/uwbnav_fuzz_rec_" + std::to_string(::getpid());
    if (::mkdir(d.c_str(), 0700) != 0 && errno != EEXIST) std::abort();
    return d;
  }();
  return dir;
}

void put(const std::string& name, const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen((scratch() + "/" + name).c_str(), "wb");
  if (f == nullptr) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
}

void put(const std::string& name, const char* text) {
  put(name, reinterpret_cast<const uint8_t*>(text), std::string(text).size());
}

void drop(const std::string& name) { std::remove((scratch() + "/" + name).c_str()); }

void check(const uwbnav::dataset::Recording& rec) {
  using namespace uwbnav;
  if (rec.site.num_anchors == 0 || rec.site.num_anchors > kMaxAnchors || rec.site.num_tags > kMaxTags) std::abort();
  uint64_t last = 0;
  for (const auto& r : rec.uwb) {
    if (!std::isfinite(r.range.range_m) || r.range.t_us < last) std::abort();
    last = r.range.t_us;
  }
  last = 0;
  for (const auto& s : rec.imu) {
    if (!std::isfinite(s.accel_body_mps2.x) || !std::isfinite(s.gyro_body_radps.z) || s.t_us < last) std::abort();
    last = s.t_us;
  }
  last = 0;
  for (const auto& g : rec.gnss) {
    if (g.fix == GnssFixType::kNone || g.rx_t_us < g.t_us || g.rx_t_us < last) std::abort();
    if (!std::isfinite(g.pos_nav_m.x) || !std::isfinite(g.pos_nav_m.y) || !std::isfinite(g.pos_nav_m.z)) std::abort();
    for (float sigma : {g.pos_sigma_m.x, g.pos_sigma_m.y, g.pos_sigma_m.z}) {
      if (!(sigma > 0.0F) || !std::isfinite(sigma)) std::abort();
    }
    if (std::isfinite(g.vel_nav_mps.x) != std::isfinite(g.vel_nav_mps.z)) std::abort();
    last = g.rx_t_us;
  }
  if (!std::isfinite(rec.site.gnss_lever_body_m.x) || !std::isfinite(rec.site.gnss_lever_body_m.z)) std::abort();
  last = 0;
  for (const auto& n : rec.neighbours) {
    if (!is_vehicle_id(n.vehicle_id) || n.rx_t_us < n.t_us || n.rx_t_us < last) std::abort();
    if (!std::isfinite(n.pos_nav_m.x) || !std::isfinite(n.pos_nav_m.y) || !std::isfinite(n.pos_nav_m.z)) std::abort();
    for (float c : n.cov_pos_m2) {
      if (!std::isfinite(c)) std::abort();
    }
    const double xx = static_cast<double>(n.cov_pos_m2[0]);
    const double xy = static_cast<double>(n.cov_pos_m2[1]);
    const double yy = static_cast<double>(n.cov_pos_m2[3]);
    if (!(xx > 0.0) || !(yy > 0.0) || !(n.cov_pos_m2[5] > 0.0F) || !(xx * yy - xy * xy > 0.0)) std::abort();
    if (std::isfinite(n.vel_nav_mps.x) != std::isfinite(n.vel_nav_mps.z)) std::abort();
    last = n.rx_t_us;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace uwbnav;
  if (size == 0 || size > 65536) return 0;
  static const char* kFiles[] = {"anchors.csv", "tags.csv", "uwb.csv", "imu.csv", "truth.csv", "meta.ini"};
  const uint8_t sel = data[0] % 10U;
  ++data;
  --size;
  if (sel == 7) {
    dataset::CalibrationFile cal;
    std::vector<std::string> errors;
    const std::string text(reinterpret_cast<const char*>(data), size);
    if (ok(dataset::parse_calibration(text, "fuzz.cal", cal, errors))) {
      for (const auto& p : cal.pairs) {
        if (!std::isfinite(p.offset_m)) std::abort();
      }
    }
    return 0;
  }
  put("anchors.csv", "anchor_id,x_m,y_m,z_m\n1,0,0,2\n2,30,0,2\n3,30,30,2\n4,0,30,2\n");
  put("tags.csv", "tag_id,x_m,y_m,z_m\n0,0,0,1\n");
  put("uwb.csv", "t_s,anchor_id,range_m\n1.0,1,10.0\n1.1,2,20.0\n");
  put("imu.csv", "t_s,ax_mps2,ay_mps2,az_mps2,gx_radps,gy_radps,gz_radps\n1.0,0,0,9.8,0,0,0\n");
  put("truth.csv", "t_s,x_m,y_m,z_m\n1.0,5,5,0\n");
  put("meta.ini", "name = fuzz\ngnss_lever_m = 0.5,0,1.5\n");
  put("gnss.csv", "t_s,x_m,y_m,z_m,sx_m,sy_m,sz_m,fix,num_sv,latency_s\n1.0,5,5,1.5,0.8,0.8,1.6,2,12,0.08\n");
  put("neighbours.csv",
      "t_s,vehicle_id,x_m,y_m,z_m,pxx_m2,pxy_m2,pxz_m2,pyy_m2,pyz_m2,pzz_m2,latency_s\n1.0,32769,15,5,1.2,0.01,0,0,0.01,0,0.04,0.05\n");
  drop("uwb.csv.gz");
  if (sel == 6) {
    drop("uwb.csv");
    put("uwb.csv.gz", data, size);
  } else if (sel == 8) {
    put("gnss.csv", data, size);
  } else if (sel == 9) {
    put("neighbours.csv", data, size);
  } else {
    put(kFiles[sel], data, size);
  }
  dataset::Recording rec;
  dataset::ReadReport rep;
  if (ok(dataset::read_recording(scratch(), rec, rep))) check(rec);
  return 0;
}
