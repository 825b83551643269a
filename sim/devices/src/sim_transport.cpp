// Simulated HID transport: paces the encoder's reports in real time (see sim_transport.hpp).
#include "mocap/devsim/sim_transport.hpp"

#include <poll.h>

#include <algorithm>
#include <cstring>

#include "mocap/core/time.hpp"

namespace mocap {

SimReportTransport::SimReportTransport(std::unique_ptr<ProtocolEncoder> enc,
                                       std::unique_ptr<Motion> motion)
    : enc_(std::move(enc)), motion_(std::move(motion)) {}

ReadResult SimReportTransport::read(std::span<uint8_t> buf, int timeout_ms, int wake_fd) {
  ReadResult r;
  const int64_t now = monotonic_ns();
  if (t0_ns_ < 0) t0_ns_ = now;
  if (queue_.empty() && enc_->streaming()) {
    // Sleep (interruptibly) until the next sample is due, then encode it.
    const int64_t due = t0_ns_ + t_device_ns_;
    const int wait_ms =
        static_cast<int>(std::clamp<int64_t>((due - now) / 1'000'000, 0, timeout_ms));
    pollfd p{wake_fd, POLLIN, 0};
    if (wait_ms > 0 && ::poll(&p, wake_fd >= 0 ? 1 : 0, wait_ms) > 0)
      return r.kind = ReadResult::kWoken, r;
    if (monotonic_ns() < due) return r;
    std::vector<uint8_t> out;
    enc_->encode(motion_->at(t_device_ns_), out);
    t_device_ns_ += static_cast<int64_t>(1e9 / enc_->rate_hz());
    const std::size_t rs = enc_->report_size();
    for (std::size_t o = 0; o + rs <= out.size(); o += rs)
      queue_.emplace_back(out.begin() + o, out.begin() + o + rs);
  } else if (queue_.empty()) {
    pollfd p{wake_fd, POLLIN, 0};
    if (::poll(&p, wake_fd >= 0 ? 1 : 0, std::min(timeout_ms, 10)) > 0)
      return r.kind = ReadResult::kWoken, r;
    t0_ns_ = monotonic_ns() - t_device_ns_;  // not streaming: the device clock waits too
    return r;
  }
  if (queue_.empty()) return r;
  const auto& rep = queue_.front();
  r.n = std::min(rep.size(), buf.size());
  std::memcpy(buf.data(), rep.data(), r.n);
  queue_.pop_front();
  r.kind = ReadResult::kData;
  return r;
}

bool SimReportTransport::write(std::span<const uint8_t> bytes, std::string&) {
  std::vector<uint8_t> reply;
  enc_->handle_host_bytes(bytes, reply);
  const std::size_t rs = enc_->report_size();
  for (std::size_t o = 0; o + rs <= reply.size(); o += rs)
    queue_.emplace_back(reply.begin() + o, reply.begin() + o + rs);
  return true;
}

int SimReportTransport::get_feature(std::span<uint8_t> buf, std::string& err) {
  std::vector<uint8_t> out;
  if (buf.empty() || !enc_->feature_report(buf[0], out)) {
    err = "simulated device has no feature report";
    return -1;
  }
  const std::size_t n = std::min(out.size(), buf.size());
  std::memcpy(buf.data(), out.data(), n);
  return static_cast<int>(n);
}

}  // namespace mocap
