// TextSource: plain or gzip text files read in chunks (see text_source.hpp).
#include "tools/dataset/text_source.hpp"

#include <sys/stat.h>
#include <zlib.h>

#include <cerrno>
#include <cstring>

namespace uwbnav::dataset {

namespace {

constexpr size_t kChunk = 1U << 16;

bool is_regular(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

bool ends_with_gz(const std::string& path) {
  return path.size() >= 3 && path.compare(path.size() - 3, 3, ".gz") == 0;
}

}  // namespace

struct TextSource::Inflater {
  z_stream zs{};
  unsigned char in[kChunk];
  bool ready = false;      // inflateInit2 succeeded
  bool in_member = false;  // inside a gzip member (header seen, end not yet)
  size_t members = 0;      // complete members inflated
};

TextSource::TextSource() = default;

TextSource::~TextSource() {
  if (z_ && z_->ready) inflateEnd(&z_->zs);
  if (f_ != nullptr) std::fclose(f_);
}

Status TextSource::open(const std::string& path) {
  path_ = path;
  if (!is_regular(path) && !ends_with_gz(path) && is_regular(path + ".gz")) path_ = path + ".gz";
  f_ = std::fopen(path_.c_str(), "rb");
  if (f_ == nullptr) {
    status_ = errno == ENOENT ? Status::kNotFound : Status::kIoError;
    error_ = path_ + (status_ == Status::kNotFound ? ": no such file" : ": cannot be opened");
    return status_;
  }
  compressed_ = ends_with_gz(path_);
  if (compressed_) {
    z_ = std::make_unique<Inflater>();
    // 15 window bits + 16: gzip wrapper only (a zlib or raw stream is corrupt input here).
    if (inflateInit2(&z_->zs, 15 + 16) != Z_OK) {
      fail("zlib initialisation failed");
      return status_;
    }
    z_->ready = true;
  }
  return Status::kOk;
}

size_t TextSource::fail(const std::string& why) {
  status_ = Status::kIoError;
  error_ = path_ + ": " + why;
  done_ = true;
  return 0;
}

size_t TextSource::read(char* buf, size_t n) {
  if (done_ || f_ == nullptr || n == 0) return 0;
  if (!compressed_) {
    const size_t got = std::fread(buf, 1, n, f_);
    if (got < n) {
      done_ = true;
      if (std::ferror(f_) != 0) return fail("read error");
    }
    return got;
  }
  return inflate_some(buf, n);
}

size_t TextSource::inflate_some(char* buf, size_t n) {
  z_stream& zs = z_->zs;
  zs.next_out = reinterpret_cast<Bytef*>(buf);
  zs.avail_out = static_cast<uInt>(n > kChunk ? kChunk : n);
  const uInt want = zs.avail_out;
  while (zs.avail_out > 0) {
    if (zs.avail_in == 0) {
      const size_t got = std::fread(z_->in, 1, kChunk, f_);
      if (got == 0) {
        if (std::ferror(f_) != 0) return fail("read error");
        if (z_->in_member) return fail("truncated gzip stream (ends inside a member)");
        if (z_->members == 0) return fail("not a gzip stream (no member)");
        done_ = true;
        break;
      }
      zs.next_in = z_->in;
      zs.avail_in = static_cast<uInt>(got);
    }
    z_->in_member = true;
    const int ret = inflate(&zs, Z_NO_FLUSH);
    if (ret == Z_STREAM_END) {
      z_->in_member = false;
      ++z_->members;
      if (inflateReset(&zs) != Z_OK) return fail("zlib reset failed");
      continue;  // a further member may follow (concatenated .gz files)
    }
    if (ret == Z_OK || ret == Z_BUF_ERROR) continue;
    return fail(std::string("corrupt gzip data (") + (zs.msg != nullptr ? zs.msg : "zlib error") + ")");
  }
  return want - zs.avail_out;
}

bool TextSource::getline(std::string& line) {
  line.clear();
  for (;;) {
    if (pending_pos_ < pending_.size()) {
      const char* b = pending_.data() + pending_pos_;
      const size_t left = pending_.size() - pending_pos_;
      const auto* nl = static_cast<const char*>(std::memchr(b, '\n', left));
      if (nl != nullptr) {
        line.append(b, static_cast<size_t>(nl - b));
        pending_pos_ += static_cast<size_t>(nl - b) + 1;
        return true;
      }
      line.append(b, left);
    }
    pending_.resize(kChunk);
    pending_pos_ = 0;
    const size_t got = read(&pending_[0], pending_.size());
    pending_.resize(got);
    if (got == 0) return status_ == Status::kOk && !line.empty();
  }
}

Status read_text_file(const std::string& path, std::string& out, std::string* error) {
  out.clear();
  TextSource src;
  Status st = src.open(path);
  if (ok(st)) {
    char buf[kChunk];
    size_t n = 0;
    while ((n = src.read(buf, sizeof buf)) > 0) out.append(buf, n);
    st = src.status();
  }
  if (!ok(st) && error != nullptr) *error = src.error();
  return st;
}

bool text_file_exists(const std::string& path) { return is_regular(path) || is_regular(path + ".gz"); }

}  // namespace uwbnav::dataset
