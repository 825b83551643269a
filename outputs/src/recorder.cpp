// SessionRecorder: the recording, a thin tap over the session module's SessionWriter.
#include "mocap/outputs/recorder.hpp"

#include <unistd.h>

#include <ctime>
#include <stdexcept>

#include "mocap/core/time.hpp"
#include "mocap/outputs/recording_file.hpp"

namespace mocap::outputs {

SessionRecorder::SessionRecorder(RecordingConfig cfg,
                                 std::function<session::SessionHeader()> header, Logger log)
    : cfg_(std::move(cfg)), header_(std::move(header)), log_(std::move(log)) {}

SessionRecorder::~SessionRecorder() {
  stop();
}

RecordTap* SessionRecorder::start(const std::string& name, bool unique) {
  if (writer_) throw std::runtime_error("already recording");
  RecordingFile f = create_recording_file(cfg_.directory, name, unique, std::time(nullptr));
  SessionWriter::Options o;
  if (cfg_.compression == "zstd") o.compression = SessionWriter::Options::Compression::zstd;
  o.compression_level = cfg_.compression_level;
  o.on_error = [this](const std::string& msg) { log_.error("recording failed: %s", msg.c_str()); };
  std::string err;
  writer_ = SessionWriter::create_fd(f.fd, f.path, header_ ? header_() : session::SessionHeader{},
                                     o, &err);
  if (!writer_) {
    ::unlinkat(f.dir_fd, f.leaf.c_str(), 0);  // our own new, empty file
    ::close(f.dir_fd);
    throw std::runtime_error(err);
  }
  ::close(f.dir_fd);
  started_ns_ = monotonic_ns();
  frames_ = samples_ = raw_blocks_ = 0;
  return this;
}

std::string SessionRecorder::path() const {
  return writer_ ? writer_->path() : std::string();
}

RecordingSummary SessionRecorder::stop() {
  RecordingSummary sum;
  if (!writer_) return sum;
  if (!writer_->close())
    log_.error("recording %s: %s", writer_->path().c_str(), writer_->stats().error.c_str());
  const auto st = writer_->stats();
  sum.path = writer_->path();
  sum.duration_s = ns_to_s(monotonic_ns() - started_ns_);
  sum.frames = frames_;
  sum.samples = samples_;
  sum.raw_blocks = raw_blocks_;
  sum.drops = st.blocks_dropped;
  sum.bytes = st.bytes_durable;
  sum.error = st.error;
  log_.info("recording %s: %.1f s, %llu frames, %llu samples, %llu blocks dropped, %llu bytes",
            sum.path.c_str(), sum.duration_s, static_cast<unsigned long long>(sum.frames),
            static_cast<unsigned long long>(sum.samples),
            static_cast<unsigned long long>(sum.drops), static_cast<unsigned long long>(sum.bytes));
  writer_.reset();
  return sum;
}

std::string SessionRecorder::error() const {
  if (!writer_) return {};
  const auto st = writer_->stats();
  return st.state == SessionWriter::State::failed ? st.error : std::string();
}

void SessionRecorder::on_raw(uint16_t device_index, int64_t t_host_ns,
                             std::span<const uint8_t> bytes) {
  if (cfg_.raw && writer_->append_raw(device_index, t_host_ns, bytes))
    raw_blocks_.fetch_add(1, std::memory_order_relaxed);
}
void SessionRecorder::on_sample(const ImuSample& s) {
  if (cfg_.samples && writer_->append_sample(s)) samples_.fetch_add(1, std::memory_order_relaxed);
}
void SessionRecorder::on_frame(const PoseFrame& f) {
  if (cfg_.poses && writer_->append_pose(f)) frames_.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace mocap::outputs
