// The simulated-device thread: truth -> encoder -> pty/UDP at the device's rate, host commands
// answered, faults injected on request (see sim_device.hpp).
#include "mocap/devsim/sim_device.hpp"

#include <time.h>

#include <array>
#include <stdexcept>

namespace mocap {

SimulatedDevice::SimulatedDevice(SimOptions opt) : opt_(std::move(opt)) {
  motion_ = opt_.motion_source ? opt_.motion_source : make_motion(opt_.motion);
  EncoderOptions eo;
  eo.rate_hz = opt_.rate_hz;
  eo.options = opt_.options;
  enc_ = make_encoder(opt_.protocol, eo);
  if (!opt_.udp.empty()) {
    udp_ = std::make_unique<UdpSender>(opt_.udp);
  } else {
    if (enc_->report_size() > 0)
      throw std::invalid_argument("protocol " + opt_.protocol +
                                  " is USB HID (record-framed): simulate it over --udp, not a pty");
    pty_ = std::make_unique<PtyEndpoint>(opt_.pty_link);
  }
}

SimulatedDevice::~SimulatedDevice() {
  stop();
}

std::string SimulatedDevice::path() const {
  std::lock_guard lk(mu_);
  return pty_ ? pty_->path() : opt_.pty_link;
}

void SimulatedDevice::start() {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this] { run(); });
}

void SimulatedDevice::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void SimulatedDevice::vanish() {
  std::lock_guard lk(mu_);
  pty_.reset();
}

void SimulatedDevice::reappear() {
  std::lock_guard lk(mu_);
  if (opt_.udp.empty() && !pty_) pty_ = std::make_unique<PtyEndpoint>(opt_.pty_link);
}

void SimulatedDevice::run() {
  std::vector<uint8_t> out, reply;
  out.reserve(4096);
  std::array<uint8_t, 512> in{};
  int64_t t_device_ns = 0;
  uint64_t k = 0;
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  uint32_t lcg = 12345;
  while (!stop_) {
    const double rate = enc_->rate_hz();
    const int64_t period_ns = static_cast<int64_t>(1e9 / rate);
    if (enc_->streaming()) {
      out.clear();
      ++k;
      const bool drop = opt_.drop_every > 0 && k % opt_.drop_every == 0;
      if (opt_.garbage_every > 0 && k % opt_.garbage_every == 0) {
        for (int i = 0; i < 7; ++i)
          out.push_back(static_cast<uint8_t>((lcg = lcg * 1103515245 + 12345) >> 16));
      }
      if (udp_ && k % 250 == 1) {  // one-way link: repeat the calibration now and then
        std::vector<uint8_t> cal;
        enc_->unsolicited(cal);
        if (!cal.empty()) {
          std::lock_guard lk(mu_);
          udp_->send(cal);  // one report (feature report sizes differ from input reports)
        }
      }
      const std::size_t start = out.size();
      enc_->encode(motion_->at(t_device_ns), out);
      if (drop) {
        out.resize(start);
        ++dropped_;
      } else if (opt_.corrupt_every > 0 && k % opt_.corrupt_every == 0 && out.size() > start + 3) {
        out[start + 4] ^= 0x5A;  // a data byte of the first frame
      }
      ++samples_;
      std::lock_guard lk(mu_);
      if (!out.empty()) {
        if (pty_) pty_->write(out);
        if (udp_) {
          const std::size_t rs = enc_->report_size();
          if (rs == 0)
            udp_->send(out);
          else
            for (std::size_t o = 0; o + rs <= out.size(); o += rs)
              udp_->send(std::span(out).subspan(o, rs));
        }
      }
    }
    t_device_ns += period_ns;
    const int64_t wall_ns =
        static_cast<int64_t>(static_cast<double>(period_ns) * (1.0 + opt_.drift_ppm * 1e-6));
    next.tv_nsec += wall_ns;
    while (next.tv_nsec >= 1'000'000'000)
      next.tv_nsec -= 1'000'000'000, ++next.tv_sec;
    // Until the next sample: answer host commands (pty only), then sleep to the deadline.
    for (;;) {
      timespec now{};
      clock_gettime(CLOCK_MONOTONIC, &now);
      const int64_t left_ms =
          ((next.tv_sec - now.tv_sec) * 1'000'000'000 + (next.tv_nsec - now.tv_nsec)) / 1'000'000;
      if (left_ms <= 0 || stop_) break;
      std::size_t n = 0;
      {
        std::lock_guard lk(mu_);
        if (!pty_) break;
        n = pty_->read(in, 0);
      }
      if (n == 0) {
        timespec slice{0, std::min<int64_t>(left_ms, 2) * 1'000'000};
        nanosleep(&slice, nullptr);
        continue;
      }
      reply.clear();
      enc_->handle_host_bytes(std::span(in.data(), n), reply);
      std::lock_guard lk(mu_);
      if (!reply.empty() && pty_) pty_->write(reply);
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
  }
}

}  // namespace mocap
