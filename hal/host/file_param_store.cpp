// Host parameter store backed by a file (see file_param_store.hpp).
#include "hal/host/file_param_store.hpp"

#include <cstdio>

namespace uwbnav::hal {

Status FileParamStore::load(uint8_t* buf, size_t cap, size_t* len) {
  std::FILE* f = std::fopen(path_.c_str(), "rb");
  if (f == nullptr) return Status::kEmpty;
  const size_t n = std::fread(buf, 1, cap, f);
  const bool more = std::fgetc(f) != EOF;
  const bool err = std::ferror(f) != 0;
  std::fclose(f);
  if (err) return Status::kIoError;
  if (more) return Status::kInvalidArgument;
  if (n == 0) return Status::kEmpty;
  *len = n;
  return Status::kOk;
}

Status FileParamStore::save(const uint8_t* buf, size_t len) {
  const std::string tmp = path_ + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (f == nullptr) return Status::kIoError;
  const bool wrote = std::fwrite(buf, 1, len, f) == len;
  const bool closed = std::fclose(f) == 0;
  if (!wrote || !closed || std::rename(tmp.c_str(), path_.c_str()) != 0) {
    std::remove(tmp.c_str());
    return Status::kIoError;
  }
  return Status::kOk;
}

}  // namespace uwbnav::hal
