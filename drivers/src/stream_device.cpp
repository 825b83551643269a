// Reader thread, set-up steps and reconnection of a live device (see stream_device.hpp).
#include "stream_device.hpp"

#include <poll.h>

#include <array>
#include <ctime>

#include "mocap/core/thread_priority.hpp"
#include "mocap/core/time.hpp"

namespace mocap {

namespace {
constexpr int kRetryMs = 200;      // reopen attempts while the device is away
constexpr int kReadSliceMs = 100;  // longest block in read (also bounds stop latency for HID)
}  // namespace

StreamDevice::StreamDevice(DeviceSpec spec, Logger log, TransportOpener open,
                           std::unique_ptr<ProtocolDecoder> decoder, std::vector<SetupStep> setup)
    : spec_(std::move(spec)),
      log_(std::move(log)),
      open_(std::move(open)),
      decoder_(std::move(decoder)),
      setup_(std::move(setup)) {
  silence_ms_ = static_cast<int>(option_double(spec_, "silence_ms", 500));
}

StreamDevice::~StreamDevice() {
  stop();
}

void StreamDevice::start(SampleSink& sink) {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this, &sink] { run(sink); });
}

void StreamDevice::stop() {
  stop_ = true;
  wake_.notify();
  if (thread_.joinable()) thread_.join();
  transport_.reset();
  std::lock_guard lk(mu_);
  stats_.connected = false;
}

DeviceStats StreamDevice::stats() const {
  std::lock_guard lk(mu_);
  return stats_;
}

bool StreamDevice::try_open(SampleSink& sink) {
  std::string err;
  transport_ = open_(err);
  if (!transport_) {
    if (err != last_open_error_) log_.warn("%s: %s (retrying)", spec_.name.c_str(), err.c_str());
    last_open_error_ = err;
    std::lock_guard lk(mu_);
    stats_.last_error = err;
    return false;
  }
  last_open_error_.clear();
  log_.info("%s: opened %s", spec_.name.c_str(), transport_->describe().c_str());
  const std::string warning = transport_->warning();
  if (!warning.empty()) log_.warn("%s: %s", spec_.name.c_str(), warning.c_str());
  {
    std::lock_guard lk(mu_);
    if (ever_opened_) ++stats_.reconnects;
    stats_.connected = true;
    if (!warning.empty()) stats_.last_error = warning;
  }
  ever_opened_ = true;
  silent_ = false;
  last_data_ns_ = monotonic_ns();
  sink.on_connection(spec_.device_index, true,
                     "opened " + transport_->describe() + (warning.empty() ? "" : "; " + warning));
  step_ = 0;
  attempts_ = 0;
  if (!setup_.empty()) begin_step(sink);
  return true;
}

void StreamDevice::lost(SampleSink& sink, const std::string& reason) {
  log_.warn("%s: lost: %s", spec_.name.c_str(), reason.c_str());
  transport_.reset();
  {
    std::lock_guard lk(mu_);
    stats_.connected = false;
    stats_.last_error = reason;
  }
  sink.on_connection(spec_.device_index, false, reason);
}

void StreamDevice::deliver(std::span<const uint8_t> bytes, int64_t t_ns, SampleSink& sink) {
  sink.on_raw(spec_.device_index, t_ns, bytes);
  decoder_->feed(bytes, t_ns, sink);
  std::lock_guard lk(mu_);
  const DecoderStats& d = decoder_->stats();
  const uint64_t n = d.samples - stats_.decoder.samples;
  // Every sample of this read timed by the device's clock: reading later changes no time.
  timed_read_ = n > 0 && d.timed_samples - stats_.decoder.timed_samples == n;
  if (n > 0) {
    // Time per sample between reads, smoothed: how many samples a batch would gather.
    if (last_read_ns_ > 0) {
      const double per = static_cast<double>(t_ns - last_read_ns_) / static_cast<double>(n);
      sample_period_ns_ =
          sample_period_ns_ > 0 ? sample_period_ns_ + 0.1 * (per - sample_period_ns_) : per;
    }
    last_read_ns_ = t_ns;
  }
  stats_.decoder = d;
}

void StreamDevice::batch_wait(int64_t t_read_ns) {
  // Fast sensors are read in batches: after a read of device-timed samples, one wake-up per
  // read_batch_ns instead of one per sample (what the samples' times say is unchanged; a
  // sample waits at most read_batch_ns longer for the pipeline). Only when a batch gathers two
  // samples or more: for a slower sensor the wait would be a wake-up more, not less.
  if (!timed_read_ || !(sample_period_ns_ > 0) ||
      2 * sample_period_ns_ > static_cast<double>(spec_.read_batch_ns))
    return;
  const int64_t left = t_read_ns + spec_.read_batch_ns - monotonic_ns();
  if (left <= 0) return;
  pollfd p{wake_.fd(), POLLIN, 0};
  const timespec ts{static_cast<time_t>(left / 1'000'000'000),
                    static_cast<long>(left % 1'000'000'000)};
  ::ppoll(&p, 1, &ts, nullptr);  // a stop() request ends it early (wake_ stays readable)
}

void StreamDevice::begin_step(SampleSink& sink) {
  const SetupStep& s = setup_[step_];
  step_deadline_ns_ = monotonic_ns() + int64_t{s.timeout_ms} * 1'000'000;
  if (s.reply_id >= 0) step_baseline_ = decoder_->replies(static_cast<uint32_t>(s.reply_id));
  std::string err;
  if (s.kind == SetupStep::kWrite) {
    if (!transport_->write(s.bytes, err))
      log_.warn("%s: %s: %s", spec_.name.c_str(), s.what, err.c_str());
  } else if (s.kind == SetupStep::kSetBaud) {
    if (!transport_->set_baud(s.baud, err))
      log_.warn("%s: %s: %s", spec_.name.c_str(), s.what, err.c_str());
  } else if (s.kind == SetupStep::kGetFeature) {
    std::array<uint8_t, 256> buf{};
    buf[0] = s.bytes.at(0);
    const int n =
        transport_->get_feature(std::span(buf.data(), std::min(s.feature_size, buf.size())), err);
    if (n > 0)
      deliver(std::span(buf.data(), static_cast<std::size_t>(n)), monotonic_ns(), sink);
    else
      log_.warn("%s: %s: %s", spec_.name.c_str(), s.what, err.c_str());
  }
}

int StreamDevice::step_poll(SampleSink& sink) {
  while (step_ < setup_.size()) {
    const SetupStep& s = setup_[step_];
    const int64_t now = monotonic_ns();
    const bool replied =
        s.reply_id >= 0 && decoder_->replies(static_cast<uint32_t>(s.reply_id)) > step_baseline_;
    if (!replied && now < step_deadline_ns_)
      return static_cast<int>(
          std::min<int64_t>((step_deadline_ns_ - now) / 1'000'000 + 1, kReadSliceMs));
    if (!replied && s.reply_id >= 0 && ++attempts_ < s.attempts) {
      begin_step(sink);
      continue;
    }
    if (!replied && s.reply_id >= 0)
      log_.warn("%s: no reply to %s after %d attempts; continuing", spec_.name.c_str(), s.what,
                s.attempts);
    attempts_ = 0;
    if (++step_ < setup_.size()) begin_step(sink);
  }
  return kReadSliceMs;
}

void StreamDevice::run(SampleSink& sink) {
  std::string rt_error;
  if (!set_this_thread_realtime(spec_.realtime_priority, &rt_error))
    log_.debug("%s: %s", spec_.name.c_str(), rt_error.c_str());  // the pipeline warns once
  std::array<uint8_t, 4096> buf{};
  while (!stop_) {
    if (!transport_ && !try_open(sink)) {
      wake_.wait(kRetryMs);
      continue;
    }
    const int timeout = step_poll(sink);
    if (!transport_) continue;
    ReadResult r = transport_->read(buf, std::min(timeout, silence_ms_ > 0 ? silence_ms_ : timeout),
                                    wake_.fd());
    const int64_t t_ns = monotonic_ns();  // timestamp at read
    switch (r.kind) {
      case ReadResult::kData:
        if (r.n == 0) break;
        if (silent_) {
          silent_ = false;
          {
            std::lock_guard lk(mu_);
            stats_.connected = true;
          }
          sink.on_connection(spec_.device_index, true, "data resumed");
        }
        last_data_ns_ = t_ns;
        deliver(std::span(buf.data(), r.n), t_ns, sink);
        // A read that filled half the buffer is behind: no wait (read on at once).
        if (spec_.read_batch_ns > 0 && r.n < buf.size() / 2) batch_wait(t_ns);
        break;
      case ReadResult::kVanished:
        lost(sink, r.reason);
        break;
      case ReadResult::kWoken:
        wake_.wait(0);
        break;
      case ReadResult::kTimeout:
        if (!silent_ && silence_ms_ > 0 &&
            t_ns - last_data_ns_ > int64_t{silence_ms_} * 1'000'000) {
          silent_ = true;
          {
            std::lock_guard lk(mu_);
            stats_.connected = false;
          }
          sink.on_connection(spec_.device_index, false,
                             "no data for " + std::to_string(silence_ms_) + " ms");
        }
        break;
    }
  }
}

}  // namespace mocap
