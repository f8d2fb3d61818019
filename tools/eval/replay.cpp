// Lockstep replay of a recording through the firmware App (see replay.hpp).
#include "tools/eval/replay.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "firmware/app.hpp"
#include "firmware/param_text.hpp"
#include "hal/host/file_param_store.hpp"
#include "hal/host/lockstep_clock.hpp"
#include "hal/host/mem_can_bus.hpp"
#include "hal/host/replay_sources.hpp"
#include "tools/eval/async_outputs.hpp"

namespace uwbnav::eval {
namespace {

// Collects what the firmware computed and hands it to the output writer.
class ReplayObserver final : public AppObserver {
 public:
  ReplayObserver(ReplayResult& result, bool keep, bool files, AsyncOutputWriter* out)
      : result_(result), keep_(keep), files_(files), out_(out) {}

  void on_range(const RangeReport& r) override {
    if (r.used) {
      ++result_.ranges_used;
    } else {
      ++result_.ranges_rejected;
    }
    if (keep_) result_.ranges.push_back(r);
    if (files_) out_->range(r);
  }
  void on_gnss(const GnssReport& g) override {
    if (g.verdict == GnssVerdict::kFused) {
      ++result_.gnss_fused;
    } else {
      ++result_.gnss_rejected;
    }
  }
  void on_output(const NavOutput& o) override {
    ++result_.epochs;
    if (o.status == NavStatus::kValid || o.status == NavStatus::kDegraded) ++result_.solution_epochs;
    if (keep_) result_.estimates.push_back(to_estimate_row(o));
    if (out_ != nullptr) out_->estimate(o);  // to estimates.csv and the sink
  }

 private:
  ReplayResult& result_;
  bool keep_;
  bool files_;
  AsyncOutputWriter* out_;  // null: neither files nor sink
};

// Hands out the rows of a streamed table as the loop reaches their time.
class StreamImuSource final : public hal::ImuSource {
 public:
  explicit StreamImuSource(dataset::RowStream<ImuSample>& rows) : rows_(rows) {}
  Status poll(uint64_t up_to_us, ImuSample& out) override {
    const ImuSample* next = rows_.peek();
    if (next == nullptr || next->t_us > up_to_us) return Status::kEmpty;
    return rows_.next(out) ? Status::kOk : Status::kEmpty;
  }
  bool finished() const override { return rows_.peek() == nullptr; }

 private:
  dataset::RowStream<ImuSample>& rows_;
};

// As StreamImuSource; the NLOS label of the row never reaches the firmware.
class StreamUwbSource final : public hal::UwbSource {
 public:
  explicit StreamUwbSource(dataset::RowStream<dataset::UwbRow>& rows) : rows_(rows) {}
  Status poll(uint64_t up_to_us, UwbRange& out) override {
    const dataset::UwbRow* next = rows_.peek();
    if (next == nullptr || next->range.t_us > up_to_us) return Status::kEmpty;
    dataset::UwbRow row;
    if (!rows_.next(row)) return Status::kEmpty;
    out = row.range;
    return Status::kOk;
  }
  bool finished() const override { return rows_.peek() == nullptr; }

 private:
  dataset::RowStream<dataset::UwbRow>& rows_;
};

uint64_t first_time_us(const ImuSample* imu, const dataset::UwbRow* uwb) {
  uint64_t t = UINT64_MAX;
  if (imu != nullptr) t = imu->t_us;
  if (uwb != nullptr && uwb->range.t_us < t) t = uwb->range.t_us;
  return t == UINT64_MAX ? 0 : t;
}

// The lockstep loop over any pair of sources starting at `t0_us`; `t_end_us`
// (0: unknown) only scales the progress line.
Status run_loop(const SiteConfig& site, hal::ImuSource& imu, hal::UwbSource& uwb, hal::GnssSource* gnss,
                hal::NeighbourSource* neighbours, uint64_t t0_us, uint64_t t_end_us, const ReplayOptions& options,
                ReplayResult& result, std::string* error) {
  const bool writing = !options.out_dir.empty();
  const bool async = writing || options.sink != nullptr;
  AsyncOutputWriter outputs;
  if (async && !ok(outputs.open(options.out_dir, "can0", options.sink))) {
    if (error) *error = "cannot write outputs to " + options.out_dir;
    return Status::kIoError;
  }
  hal::LockstepClock clock;
  hal::MemCanBus bus;
  AsyncCanLogTee logged_bus(bus, outputs);
  hal::CanBus& can = writing ? static_cast<hal::CanBus&>(logged_bus) : bus;
  hal::NullSerialPort serial;
  hal::EmptyParamStore store;
  hal::Board board{imu, uwb, can, serial, clock, store, site, gnss, neighbours};

  App app(board);
  if (!ok(app.init())) {
    if (error) *error = "the firmware rejected the site configuration (anchors/tags, or an unusable range calibration)";
    return Status::kInvalidArgument;
  }
  for (const auto& [name, value] : options.params) {
    const ParamDef* d = nullptr;
    char why[kParamErrorMax];
    const Status checked = check_param_value(name.c_str(), value, &d, why, sizeof why);
    if (!ok(checked) || !ok(app.set_param(d->index, value))) {
      if (error) *error = std::string("param: ") + why;
      return ok(checked) ? Status::kInvalidArgument : checked;
    }
  }

  ReplayObserver observer(result, options.keep_in_memory, writing, async ? &outputs : nullptr);
  app.set_observer(&observer);

  // Loop time on the 10 ms grid, starting at the cycle that holds the first sample.
  uint64_t t = (t0_us / kCyclePeriodUs + 1) * kCyclePeriodUs;
  const auto wall0 = std::chrono::steady_clock::now();
  uint64_t next_progress = 0;
  for (;;) {
    clock.sleep_until_us(t);
    app.tick(t);
    ++result.cycles;
    // Drain what the firmware sent so the in-memory bus never fills.
    hal::CanFrame f;
    while (ok(bus.receive_sent(f))) ++result.can_frames;
    if (options.progress && result.cycles >= next_progress) {
      if (t_end_us > t0_us) {
        std::fprintf(stderr, "\rreplay %5.1f %%", 100.0 * static_cast<double>(t - t0_us) / static_cast<double>(t_end_us - t0_us));
      } else {
        std::fprintf(stderr, "\rreplay t = %.0f s", dataset::us_to_seconds(t));
      }
      next_progress = result.cycles + 10000;
    }
    if (imu.finished() && uwb.finished()) break;
    t += kCyclePeriodUs;
  }
  const auto wall1 = std::chrono::steady_clock::now();
  if (options.progress) std::fprintf(stderr, "\rreplay done%20s\n", "");
  result.wall_s = std::chrono::duration<double>(wall1 - wall0).count();
  result.stats = app.stats();
  result.diag = app.navigator().diagnostics();
  if (!ok(outputs.close())) {
    if (error) *error = "writing outputs to " + options.out_dir + " failed";
    return Status::kIoError;
  }
  return Status::kOk;
}

}  // namespace

dataset::EstimateRow to_estimate_row(const NavOutput& o) {
  dataset::EstimateRow r;
  r.t_us = o.t_us;
  r.pos_nav_m[0] = o.pos_nav_m.x;
  r.pos_nav_m[1] = o.pos_nav_m.y;
  r.pos_nav_m[2] = o.pos_nav_m.z;
  r.vel_nav_mps[0] = o.vel_nav_mps.x;
  r.vel_nav_mps[1] = o.vel_nav_mps.y;
  r.vel_nav_mps[2] = o.vel_nav_mps.z;
  for (int k = 0; k < 4; ++k) r.q_nav_body[k] = o.q_nav_body[k];
  r.pos_sigma_m[0] = o.pos_sigma_m.x;
  r.pos_sigma_m[1] = o.pos_sigma_m.y;
  r.pos_sigma_m[2] = o.pos_sigma_m.z;
  r.status = static_cast<int>(o.status);
  r.mode = static_cast<int>(o.mode);
  r.pos_xy_corr = o.pos_xy_corr;
  return r;
}

Status run_replay(const dataset::Recording& rec, const ReplayOptions& options, ReplayResult& result,
                  std::string* error) {
  result = ReplayResult{};
  hal::ReplaySources sources(rec);
  const uint64_t t0 = first_time_us(rec.imu.empty() ? nullptr : &rec.imu.front(),
                                    rec.uwb.empty() ? nullptr : &rec.uwb.front());
  const uint64_t t_end = std::max(rec.imu.empty() ? 0 : rec.imu.back().t_us,
                                  rec.uwb.empty() ? 0 : rec.uwb.back().range.t_us);
  if (options.keep_in_memory) {
    const size_t n = rec.imu.empty() ? rec.uwb.size() : rec.imu.size();
    result.estimates.reserve(n + 16);
    result.ranges.reserve(rec.uwb.size());
  }
  return run_loop(rec.site, sources.imu, sources.uwb, sources.gnss_or_null(rec), sources.neighbours_or_null(rec), t0,
                  t_end, options, result, error);
}

Status run_replay(dataset::RecordingStream& rec, const ReplayOptions& options, ReplayResult& result,
                  std::string* error) {
  result = ReplayResult{};
  StreamImuSource imu(rec.imu);
  StreamUwbSource uwb(rec.uwb);
  hal::ReplayGnssSource gnss(rec.gnss);  // gnss.csv is small (a few hertz): read whole
  hal::ReplayNeighbourSource neighbours(rec.neighbours);  // neighbours.csv likewise
  const uint64_t t0 = first_time_us(rec.imu.peek(), rec.uwb.peek());
  return run_loop(rec.site, imu, uwb, rec.gnss.empty() ? nullptr : &gnss,
                  rec.neighbours.empty() ? nullptr : &neighbours, t0, 0, options, result, error);
}

}  // namespace uwbnav::eval
