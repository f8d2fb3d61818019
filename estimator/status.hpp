// Error handling without exceptions: a [[nodiscard]] status code and a result
// type carrying either a value or a status. Shared by estimator/, hal/ and firmware/.
#pragma once

#include <cstdint>

namespace uwbnav {

enum class [[nodiscard]] Status : uint8_t {
  kOk = 0,
  kInvalidArgument,  // caller passed something malformed (NaN, bad id, bad size)
  kOutOfRange,       // value outside its documented physical/param range
  kNotFinite,        // NaN or Inf in an input or a computed quantity
  kFull,             // fixed-capacity container full; the item was NOT stored
  kEmpty,            // nothing available (no frame due, empty queue)
  kNotInitialised,   // object used before configure()/initialisation
  kRejected,         // measurement rejected by a gate or a consistency check
  kSingular,         // geometry or matrix singular / ill conditioned
  kIoError,          // HAL-level I/O failure
  kWouldBlock,       // non-blocking call could not proceed now; retry later
  kUnsupported,      // feature not available on this board/build
  kNotFound,         // lookup by id/name failed
};

// Short stable name for logs and console output.
constexpr const char* status_name(Status s) {
  switch (s) {
    case Status::kOk: return "ok";
    case Status::kInvalidArgument: return "invalid_argument";
    case Status::kOutOfRange: return "out_of_range";
    case Status::kNotFinite: return "not_finite";
    case Status::kFull: return "full";
    case Status::kEmpty: return "empty";
    case Status::kNotInitialised: return "not_initialised";
    case Status::kRejected: return "rejected";
    case Status::kSingular: return "singular";
    case Status::kIoError: return "io_error";
    case Status::kWouldBlock: return "would_block";
    case Status::kUnsupported: return "unsupported";
    case Status::kNotFound: return "not_found";
  }
  return "unknown";
}

constexpr bool ok(Status s) { return s == Status::kOk; }

// Explicitly discard a status where ignoring it is the intended behaviour.
constexpr void ignore_status(Status) {}
constexpr void ignore_result(bool) {}

// Value-or-status. T must be default constructible (firmware types are PODs).
template <typename T>
class [[nodiscard]] Result {
 public:
  constexpr Result(const T& value) : value_(value), status_(Status::kOk) {}  // NOLINT(google-explicit-constructor)
  constexpr Result(Status status) : value_(), status_(status) {}            // NOLINT(google-explicit-constructor)

  constexpr bool ok() const { return status_ == Status::kOk; }
  constexpr Status status() const { return status_; }
  constexpr const T& value() const { return value_; }
  constexpr T& value() { return value_; }
  constexpr const T& value_or(const T& fallback) const { return ok() ? value_ : fallback; }

 private:
  T value_;
  Status status_;
};

}  // namespace uwbnav
