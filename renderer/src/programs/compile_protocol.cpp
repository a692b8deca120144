#include "programs/compile_protocol.h"

#include <limits.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

namespace brdfa::compile_protocol {
namespace {

class Writer {
 public:
  void u32(uint32_t v) { raw(&v, sizeof v); }
  void i32(int32_t v) { raw(&v, sizeof v); }
  void f64(double v) { raw(&v, sizeof v); }
  void str(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    out_ += s;
  }
  void raw(const void* p, size_t n) { out_.append(static_cast<const char*>(p), n); }
  void diagnostics(const std::vector<Diagnostic>& ds) {
    u32(static_cast<uint32_t>(ds.size()));
    for (const Diagnostic& d : ds) {
      i32(d.line);
      i32(d.column);
      str(d.severity);
      str(d.message);
    }
  }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

// Every read is bounds-checked: a short or garbled frame fails (ok() false), never overreads.
class Reader {
 public:
  explicit Reader(const std::string& in) : in_(in) {}
  bool ok() const { return ok_; }
  bool done() const { return ok_ && at_ == in_.size(); }
  uint32_t u32() {
    uint32_t v = 0;
    raw(&v, sizeof v);
    return v;
  }
  int32_t i32() {
    int32_t v = 0;
    raw(&v, sizeof v);
    return v;
  }
  double f64() {
    double v = 0;
    raw(&v, sizeof v);
    return v;
  }
  std::string str() {
    const uint32_t n = u32();
    if (!ok_ || n > in_.size() - at_) return fail(), std::string();
    std::string s = in_.substr(at_, n);
    at_ += n;
    return s;
  }
  void raw(void* p, size_t n) {
    if (!ok_ || n > in_.size() - at_) return fail();
    std::memcpy(p, in_.data() + at_, n);
    at_ += n;
  }
  std::vector<Diagnostic> diagnostics() {
    std::vector<Diagnostic> ds;
    const uint32_t n = u32();
    for (uint32_t i = 0; ok_ && i < n; ++i) {
      Diagnostic d;
      d.line = i32();
      d.column = i32();
      d.severity = str();
      d.message = str();
      ds.push_back(std::move(d));
    }
    return ds;
  }

 private:
  void fail() { ok_ = false; }
  const std::string& in_;
  size_t at_ = 0;
  bool ok_ = true;
};

}  // namespace

std::string encodeRequest(ShaderStage stage, const std::string& source) {
  Writer w;
  w.u32(static_cast<uint32_t>(stage));
  w.raw(source.data(), source.size());
  return w.take();
}

bool decodeRequest(const std::string& frame, ShaderStage& stage, std::string& source) {
  Reader r(frame);
  const uint32_t s = r.u32();
  if (!r.ok() || s > static_cast<uint32_t>(ShaderStage::Fragment)) return false;
  stage = static_cast<ShaderStage>(s);
  source = frame.substr(sizeof(uint32_t));
  return true;
}

std::string encodeReply(const Result<SpirvBinary>& result) {
  Writer w;
  w.u32(result.ok() ? 1u : 0u);
  if (result.ok()) {
    w.f64(result->compileMs);
    w.u32(static_cast<uint32_t>(result->words.size()));
    w.raw(result->words.data(), result->words.size() * sizeof(uint32_t));
    w.diagnostics(result->warnings);
  } else {
    w.u32(static_cast<uint32_t>(result.error().code));
    w.str(result.error().message);
    w.diagnostics(result.error().diagnostics);
  }
  return w.take();
}

std::optional<Result<SpirvBinary>> decodeReply(const std::string& frame) {
  Reader r(frame);
  const uint32_t ok = r.u32();
  if (!r.ok()) return std::nullopt;
  if (ok == 1u) {
    SpirvBinary b;
    b.compileMs = r.f64();
    const uint32_t words = r.u32();
    if (!r.ok() || words > frame.size() / sizeof(uint32_t)) return std::nullopt;
    b.words.resize(words);
    r.raw(b.words.data(), words * sizeof(uint32_t));
    b.warnings = r.diagnostics();
    if (!r.done()) return std::nullopt;
    return Result<SpirvBinary>(std::move(b));
  }
  Error e;
  e.code = static_cast<ErrorCode>(r.u32());
  e.message = r.str();
  e.diagnostics = r.diagnostics();
  if (!r.done()) return std::nullopt;
  return Result<SpirvBinary>(std::move(e));
}

bool writeFrame(int fd, const std::string& payload) { return writeFrameParts(fd, {payload}); }

bool writeFrameParts(int fd, std::initializer_list<std::string_view> parts) {
  size_t total = 0;
  for (std::string_view p : parts) total += p.size();
  const uint32_t n = static_cast<uint32_t>(total);
  std::vector<iovec> iov;
  iov.push_back({const_cast<uint32_t*>(&n), sizeof n});
  for (std::string_view p : parts)
    if (!p.empty()) iov.push_back({const_cast<char*>(p.data()), p.size()});
  size_t first = 0;  // the first iovec not yet sent whole
  while (first < iov.size()) {
    msghdr msg{};
    msg.msg_iov = iov.data() + first;
    msg.msg_iovlen = std::min<size_t>(iov.size() - first, IOV_MAX);
    // MSG_NOSIGNAL: a worker that died must not take the server down with SIGPIPE.
    const ssize_t k = ::sendmsg(fd, &msg, MSG_NOSIGNAL);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    for (size_t sent = size_t(k); sent > 0;) {  // drop what went out, part of an iovec included
      const size_t here = std::min(sent, iov[first].iov_len);
      iov[first].iov_base = static_cast<char*>(iov[first].iov_base) + here;
      iov[first].iov_len -= here;
      sent -= here;
      if (iov[first].iov_len == 0) ++first;
    }
  }
  return true;
}

namespace {
bool readAll(int fd, char* p, size_t n) {
  while (n > 0) {
    const ssize_t k = ::read(fd, p, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    p += k;
    n -= static_cast<size_t>(k);
  }
  return true;
}
}  // namespace

bool readFrame(int fd, std::string& payload, uint32_t maxBytes) {
  uint32_t n = 0;
  if (!readAll(fd, reinterpret_cast<char*>(&n), sizeof n) || n > maxBytes) return false;
  payload.assign(n, '\0');
  return readAll(fd, payload.data(), n);
}

}  // namespace brdfa::compile_protocol
