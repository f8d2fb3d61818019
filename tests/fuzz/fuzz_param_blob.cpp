// libFuzzer target: the parameter blob loader (what flash holds). A blob that
// loads must leave every parameter finite, in [min, max] and whole where the
// kind asks, and write back to a blob that reads to the same values; the App
// must start from any stored blob (defaults when it is refused).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>

#include "estimator/params.hpp"
#include "firmware/app.hpp"
#include "firmware/param_blob.hpp"
#include "tests/fuzz/fuzz_board.hpp"

namespace {

void check_in_range(const uwbnav::Params& p) {
  using namespace uwbnav;
  for (size_t i = 0; i < kNumParams; ++i) {
    const ParamDef& d = kParamDefs[i];
    const float v = p.get(d.index);
    if (!std::isfinite(v) || v < d.min || v > d.max) std::abort();
    if (d.kind != ParamKind::kReal && std::floor(v) != v) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace uwbnav;
  Params p;
  ParamBlobReport rep;
  const Status st = param_blob_read(data, size, p, &rep);
  if (st == Status::kOk) {
    check_in_range(p);
    uint8_t buf[kParamBlobMaxBytes];
    const size_t n = param_blob_write(p, buf, sizeof buf);
    if (n == 0) std::abort();
    Params q;
    if (!ok(param_blob_read(buf, n, q, nullptr))) std::abort();
    for (size_t i = 0; i < kNumParams; ++i) {
      if (q.get(kParamDefs[i].index) != p.get(kParamDefs[i].index)) std::abort();
    }
  } else {
    // Refused: untouched.
    const Params defaults;
    for (size_t i = 0; i < kNumParams; ++i) {
      if (p.get(kParamDefs[i].index) != defaults.get(kParamDefs[i].index)) std::abort();
    }
  }

  static const SiteConfig site = fuzz::square_site(true, Platform::kGround);
  fuzz::VectorImuSource imu;
  fuzz::VectorUwbSource uwb;
  fuzz::SinkCanBus can;
  fuzz::StringSerial serial;
  fuzz::StepClock clock;
  fuzz::BlobParamStore store;
  store.blob.assign(data, data + size);
  store.present = true;
  hal::Board board{imu, uwb, can, serial, clock, store, site};
  auto app = std::make_unique<App>(board);
  if (!ok(app->init())) std::abort();
  check_in_range(app->params());
  app->tick(1000000);
  return 0;
}
