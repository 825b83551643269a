// The generic live device (internal): opens its transport, runs the protocol's set-up steps,
// reads on one thread (timestamp at read), decodes, and reconnects by itself.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

#include "mocap/core/log.hpp"
#include "mocap/core/wakeup.hpp"
#include "mocap/drivers/transport.hpp"
#include "protocols.hpp"

namespace mocap {

using TransportOpener = std::function<std::unique_ptr<ByteTransport>(std::string& err)>;

class StreamDevice final : public Device {
 public:
  StreamDevice(DeviceSpec spec, Logger log, TransportOpener open,
               std::unique_ptr<ProtocolDecoder> decoder, std::vector<SetupStep> setup);
  ~StreamDevice() override;
  void start(SampleSink& sink) override;
  void stop() override;
  DeviceStats stats() const override;
  const DeviceSpec& spec() const override { return spec_; }

 private:
  void run(SampleSink& sink);
  bool try_open(SampleSink& sink);
  void lost(SampleSink& sink, const std::string& reason);
  void deliver(std::span<const uint8_t> bytes, int64_t t_ns, SampleSink& sink);
  /// DeviceSpec::read_batch_ns: after a read of device-timed samples, waits until that long
  /// after it (or a stop request).
  void batch_wait(int64_t t_read_ns);
  void begin_step(SampleSink& sink);
  int step_poll(SampleSink& sink);  ///< advances set-up; returns the read timeout to use

  DeviceSpec spec_;
  Logger log_;
  TransportOpener open_;
  std::unique_ptr<ProtocolDecoder> decoder_;
  std::vector<SetupStep> setup_;
  std::unique_ptr<ByteTransport> transport_;
  Wakeup wake_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  int silence_ms_ = 500;

  // Reader-thread state.
  std::size_t step_ = 0;
  int attempts_ = 0;
  int64_t step_deadline_ns_ = 0;
  uint64_t step_baseline_ = 0;
  int64_t last_data_ns_ = 0;
  bool timed_read_ = false;      ///< the last read's samples all carried the device's time
  int64_t last_read_ns_ = 0;     ///< the last read that gave samples
  double sample_period_ns_ = 0;  ///< time per sample between reads, smoothed
  bool silent_ = false, ever_opened_ = false;
  std::string last_open_error_;

  mutable std::mutex mu_;
  DeviceStats stats_;
};

}  // namespace mocap
