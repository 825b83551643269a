// A simulated record-framed device behind the ByteTransport interface: a HID controller
// (DS4, DualSense, Joy-Con) whose input reports, feature reports and replies to output reports
// come from its ProtocolEncoder at the device's rate. The real StreamDevice (set-up steps,
// reader thread, decoder) runs on it exactly as on hidapi.
#pragma once

#include <deque>
#include <memory>

#include "mocap/devsim/sim_device.hpp"
#include "mocap/drivers/device.hpp"
#include "mocap/drivers/transport.hpp"

namespace mocap {

class SimReportTransport final : public ByteTransport {
 public:
  SimReportTransport(std::unique_ptr<ProtocolEncoder> enc, std::unique_ptr<Motion> motion);
  ReadResult read(std::span<uint8_t> buf, int timeout_ms, int wake_fd) override;
  bool write(std::span<const uint8_t> bytes, std::string& err) override;
  int get_feature(std::span<uint8_t> buf, std::string& err) override;
  bool record_framed() const override { return true; }
  std::string describe() const override { return "simulated HID device"; }

 private:
  std::unique_ptr<ProtocolEncoder> enc_;
  std::unique_ptr<Motion> motion_;
  std::deque<std::vector<uint8_t>> queue_;  ///< replies and reports waiting to be read
  int64_t t0_ns_ = -1, t_device_ns_ = 0;
};

}  // namespace mocap
