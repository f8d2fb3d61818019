// Host parameter store: the NV blob in a file, written atomically (temp + rename).
#pragma once

#include <string>

#include "hal/hal.hpp"

namespace uwbnav::hal {

class FileParamStore final : public ParamStore {
 public:
  explicit FileParamStore(std::string path) : path_(std::move(path)) {}
  [[nodiscard]] Status load(uint8_t* buf, size_t cap, size_t* len) override;
  [[nodiscard]] Status save(const uint8_t* buf, size_t len) override;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// A store that holds nothing and refuses writes (batch replay: defaults only).
class EmptyParamStore final : public ParamStore {
 public:
  [[nodiscard]] Status load(uint8_t*, size_t, size_t*) override { return Status::kEmpty; }
  [[nodiscard]] Status save(const uint8_t*, size_t) override { return Status::kUnsupported; }
};

// Serial port with nobody attached: reads nothing, accepts and discards output.
class NullSerialPort final : public SerialPort {
 public:
  size_t read(uint8_t*, size_t) override { return 0; }
  size_t write(const uint8_t*, size_t len) override { return len; }
};

}  // namespace uwbnav::hal
