// Byte and line source over a text file that may be gzip-compressed: opens
// X, or X.gz when X is absent, and inflates .gz input in fixed-size chunks
// (zlib streaming, multi-member files accepted, truncation and corruption reported).
#pragma once

#include <cstddef>
#include <cstdio>
#include <memory>
#include <string>

#include "estimator/status.hpp"

namespace uwbnav::dataset {

class TextSource {
 public:
  TextSource();
  ~TextSource();
  TextSource(const TextSource&) = delete;
  TextSource& operator=(const TextSource&) = delete;

  // Opens `path`; when it does not exist, `path` + ".gz". kNotFound when
  // neither exists, kIoError when the file cannot be opened. A file whose name
  // ends in ".gz" is always inflated.
  [[nodiscard]] Status open(const std::string& path);

  // Reads up to `n` bytes into `buf`; returns the count, 0 at the end of the
  // data or on an error (then status() is not kOk and error() says why).
  size_t read(char* buf, size_t n);

  // Next line without its '\n' (a trailing '\r' is kept). False at the end or on an error.
  bool getline(std::string& line);

  Status status() const { return status_; }
  const std::string& error() const { return error_; }
  // The file actually opened (X or X.gz).
  const std::string& path() const { return path_; }
  bool compressed() const { return compressed_; }

 private:
  size_t inflate_some(char* buf, size_t n);
  size_t fail(const std::string& why);

  struct Inflater;
  std::FILE* f_ = nullptr;
  std::unique_ptr<Inflater> z_;
  std::string path_;
  std::string error_;
  Status status_ = Status::kOk;
  bool compressed_ = false;
  bool done_ = false;
  std::string pending_;  // getline(): bytes read past the last returned line
  size_t pending_pos_ = 0;
};

// Whole content of `path` (or `path`.gz) into `out`. kNotFound when neither
// exists; kIoError on a read error or a truncated/corrupt .gz, with `error`
// ("file.csv.gz: truncated gzip stream") set when non-null.
[[nodiscard]] Status read_text_file(const std::string& path, std::string& out, std::string* error = nullptr);

// True when `path` or `path`.gz is a regular file.
bool text_file_exists(const std::string& path);

}  // namespace uwbnav::dataset
