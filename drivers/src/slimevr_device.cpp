// The live SlimeVR input: one UDP socket (default 0.0.0.0:6969) and one reader thread for all
// trackers of a rig. Each datagram becomes an addressed record (recorded raw, then decoded by
// SlimeVrDecoder); the decoder's replies (handshake, acks, heartbeats, pings) go back with
// sendto, so unmodified tracker firmware connects. Also `listen_slimevr_hellos` for
// `mocap devices`.
#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <thread>

#include "decoders.hpp"
#include "mocap/core/thread_priority.hpp"
#include "mocap/core/time.hpp"
#include "mocap/core/wakeup.hpp"
#include "mocap/drivers/slimevr_listen.hpp"
#include "slimevr_decoder.hpp"
#include "udp_socket.hpp"

namespace mocap {

namespace {

constexpr int kTickMs = 100;
constexpr int kRetryMs = 500;
constexpr int64_t kHelloRecordNs = 250'000'000;  // boards' handshakes re-recorded this often

/// The server's socket: IPv4 (the trackers speak IPv4), broadcast-capable. -1 + err on failure.
int bind_udp4(const std::string& host_port, std::string& err) {
  return bind_udp(host_port, /*ipv4_only=*/true, /*broadcast=*/true, err);
}

std::string udp_address(const DeviceSpec& spec) {
  if (spec.port.empty()) return "0.0.0.0:" + std::to_string(slimevr::kDefaultPort);
  if (spec.port.rfind("udp:", 0) == 0) return spec.port.substr(4);
  throw std::invalid_argument("device " + spec.name +
                              ": a slimevr port is udp:HOST:PORT (default udp:0.0.0.0:6969)");
}

class SlimeVrDevice final : public Device {
 public:
  SlimeVrDevice(DeviceSpec spec, Logger log)
      : spec_(std::move(spec)), log_(std::move(log)), addr_(udp_address(spec_)), dec_(spec_) {}
  ~SlimeVrDevice() override { stop(); }

  void start(SampleSink& sink) override {
    if (thread_.joinable()) return;
    stop_ = false;
    thread_ = std::thread([this, &sink] { run(sink); });
  }
  void stop() override {
    stop_ = true;
    wake_.notify();
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    std::lock_guard lk(mu_);
    stats_.connected = false;
  }
  DeviceStats stats() const override {
    std::lock_guard lk(mu_);
    return stats_;
  }
  const DeviceSpec& spec() const override { return spec_; }

 private:
  void send_replies() {
    for (const auto& r : dec_.pending_replies()) {
      sockaddr_in to{};
      to.sin_family = AF_INET;
      to.sin_addr.s_addr = htonl(r.ip);
      to.sin_port = htons(r.port);
      ::sendto(fd_, r.bytes.data(), r.len, MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&to),
               sizeof to);
    }
    dec_.clear_replies();
  }

  void run(SampleSink& sink) {
    std::string rt_error;
    if (!set_this_thread_realtime(spec_.realtime_priority, &rt_error))
      log_.debug("%s: %s", spec_.name.c_str(), rt_error.c_str());
    std::array<uint8_t, 2048> buf{};
    std::size_t known_boards = 0;
    while (!stop_) {
      if (fd_ < 0) {
        std::string err;
        fd_ = bind_udp4(addr_, err);
        if (fd_ < 0) {
          if (err != last_error_) log_.warn("%s: %s (retrying)", spec_.name.c_str(), err.c_str());
          last_error_ = err;
          std::lock_guard lk(mu_);
          stats_.last_error = err;
          wake_.wait(kRetryMs);
          continue;
        }
        log_.info("%s: listening for SlimeVR trackers on udp %s", spec_.name.c_str(),
                  addr_.c_str());
        std::lock_guard lk(mu_);
        stats_.connected = true;
      }
      pollfd p[2] = {{fd_, POLLIN, 0}, {wake_.fd(), POLLIN, 0}};
      const int n = ::poll(p, 2, kTickMs);
      if (n > 0 && (p[1].revents & POLLIN)) wake_.wait(0);
      if (n > 0 && (p[0].revents & POLLIN)) {
        sockaddr_in from{};
        socklen_t len = sizeof from;
        const ssize_t got =
            ::recvfrom(fd_, buf.data() + kSlimeRecordHeader, buf.size() - kSlimeRecordHeader,
                       MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&from), &len);
        const int64_t t_ns = monotonic_ns();  // timestamp at read
        if (got > 0 && from.sin_family == AF_INET) {
          const uint32_t ip = ntohl(from.sin_addr.s_addr);
          const uint16_t port = ntohs(from.sin_port);
          buf[0] = static_cast<uint8_t>(ip >> 24);
          buf[1] = static_cast<uint8_t>(ip >> 16);
          buf[2] = static_cast<uint8_t>(ip >> 8);
          buf[3] = static_cast<uint8_t>(ip);
          buf[4] = static_cast<uint8_t>(port >> 8);
          buf[5] = static_cast<uint8_t>(port);
          const std::span<const uint8_t> rec(buf.data(), kSlimeRecordHeader + got);
          sink.on_raw(spec_.device_index, t_ns, rec);
          dec_.feed(rec, t_ns, sink);
        }
      }
      const int64_t now = monotonic_ns();
      if (now - last_tick_ns_ >= int64_t{kTickMs} * 1'000'000) {
        last_tick_ns_ = now;
        dec_.tick(now, sink);
        if (now - last_hello_ns_ >= kHelloRecordNs) {
          last_hello_ns_ = now;
          // Into the recording only (not decoded again here): a take started later still has
          // each board's handshake before its data, so raw replay knows the boards' MACs.
          dec_.each_hello_record(
              [&](std::span<const uint8_t> rec) { sink.on_raw(spec_.device_index, now, rec); });
        }
        if (dec_.board_count() != known_boards) {  // (a list only when boards come or go)
          for (const auto& b : dec_.boards())
            log_.info("%s: tracker %s at %u.%u.%u.%u (firmware \"%s\", protocol %u)",
                      spec_.name.c_str(), slimevr::mac_string(b.mac).c_str(), b.ip >> 24,
                      b.ip >> 16 & 255, b.ip >> 8 & 255, b.ip & 255, b.firmware.c_str(),
                      b.protocol_version);
          known_boards = dec_.board_count();
        }
      }
      send_replies();
      std::lock_guard lk(mu_);
      stats_.decoder = dec_.stats();
    }
  }

  DeviceSpec spec_;
  Logger log_;
  std::string addr_;
  SlimeVrDecoder dec_;
  int fd_ = -1;
  Wakeup wake_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  int64_t last_tick_ns_ = 0, last_hello_ns_ = 0;
  std::string last_error_;
  mutable std::mutex mu_;
  DeviceStats stats_;
};

}  // namespace

std::unique_ptr<Device> make_slimevr_device(const DeviceSpec& spec, Logger log) {
  return std::make_unique<SlimeVrDevice>(spec, std::move(log));
}

std::vector<SlimeVrHello> listen_slimevr_hellos(const std::string& host_port, int ms,
                                                std::string& err) {
  std::vector<SlimeVrHello> out;
  const int fd = bind_udp4(host_port, err);
  if (fd < 0) return out;
  const int64_t end = monotonic_ns() + int64_t{ms} * 1'000'000;
  std::array<uint8_t, 2048> buf{};
  std::array<slimevr::Packet, slimevr::kMaxPackets> packets{};
  for (int64_t now = monotonic_ns(); now < end; now = monotonic_ns()) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>((end - now) / 1'000'000) + 1) <= 0) continue;
    sockaddr_in from{};
    socklen_t len = sizeof from;
    const ssize_t got = ::recvfrom(fd, buf.data(), buf.size(), MSG_DONTWAIT,
                                   reinterpret_cast<sockaddr*>(&from), &len);
    if (got <= 0) continue;
    slimevr::Error e;
    const std::size_t n =
        slimevr::parse_datagram(std::span(buf.data(), static_cast<std::size_t>(got)), packets, e);
    for (std::size_t i = 0; i < n; ++i) {
      const auto& pk = packets[i];
      if (pk.type != slimevr::kHandshake || !pk.has_mac) continue;
      bool seen = false;
      for (const auto& h : out)
        seen = seen || h.mac == slimevr::mac_string(pk.mac);
      if (seen) continue;
      char ip[INET_ADDRSTRLEN] = "";
      ::inet_ntop(AF_INET, &from.sin_addr, ip, sizeof ip);
      out.push_back({slimevr::mac_string(pk.mac), ip, pk.board, pk.handshake_imu, pk.mcu,
                     pk.protocol_version, std::string(pk.firmware_text())});
    }
  }
  ::close(fd);
  return out;
}

}  // namespace mocap
