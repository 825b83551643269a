// run_replay with the per-sensor filters on a pool of threads (ReplayOptions::filter_threads):
// samples are read in chunks; each chunk's filter steps (PoseEngine::prefilter, one task per
// sensor, in that sensor's sample order) run on the pool and the replay thread while the replay
// thread takes the previous chunk through the rest of the pipeline (PipelineCore::process with
// the filter's output) in sample order. Every sensor's filter sees the same samples in the same
// order as in a sequential replay and every other step runs in the same order on one thread, so
// the frames are bit-identical. A chunk ends before the sample at which the replay asks for a
// calibration; from there samples go through the whole pipeline one by one until the capture
// is over (its end hands suspected local fields to the filters, which must be in step).
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "mocap/core/time.hpp"
#include "mocap/daemon/replay.hpp"

namespace mocap::daemon {

namespace {

constexpr std::size_t kChunkSamples = 4096;

/// One chunk of the input: the samples, the input's wall-clock offset with each, and (once
/// prefiltered) each accepted sample's filter output.
struct Chunk {
  std::vector<ImuSample> samples;
  std::vector<int64_t> offsets;
  std::vector<uint8_t> offset_known;
  std::vector<FilterOutput> outputs;
  std::vector<std::vector<uint32_t>> by_sensor;  ///< accepted samples' indexes, per sensor
  bool prefiltered = false;
  bool ends_input = false;
};

/// Runs a chunk's per-sensor filter tasks on `threads` threads plus whoever calls help().
class FilterPool {
 public:
  FilterPool(PoseEngine& engine, int threads) : engine_(engine) {
    for (int k = 0; k < threads; ++k)
      threads_.emplace_back([this] { work(); });
  }
  ~FilterPool() {
    {
      std::lock_guard lock(mu_);
      stop_ = true;
    }
    cv_.notify_all();
    for (auto& t : threads_)
      t.join();
  }
  /// Starts the chunk's tasks (the pool must be idle).
  void start(Chunk& c) {
    {
      std::lock_guard lock(mu_);
      chunk_ = &c;
      next_ = 0;
      left_ = c.by_sensor.size();
      ++generation_;
    }
    cv_.notify_all();
  }
  /// Takes tasks of the started chunk until none is left, then waits until all are done.
  void help_and_wait() {
    run_tasks();
    std::unique_lock lock(mu_);
    done_cv_.wait(lock, [&] { return left_ == 0; });
    chunk_ = nullptr;
  }

 private:
  void work() {
    uint64_t seen = 0;
    for (;;) {
      {
        std::unique_lock lock(mu_);
        cv_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
      }
      run_tasks();
    }
  }
  /// Claims tasks of the current chunk one at a time (under the lock, so a task always
  /// belongs to the chunk it was claimed from) and runs them.
  void run_tasks() {
    for (;;) {
      Chunk* c = nullptr;
      std::size_t t = 0;
      {
        std::lock_guard lock(mu_);
        if (!chunk_ || next_ >= chunk_->by_sensor.size()) return;
        c = chunk_;
        t = next_++;
      }
      for (const uint32_t k : c->by_sensor[t])
        c->outputs[k] = engine_.prefilter(static_cast<int>(t), c->samples[k]);
      std::lock_guard lock(mu_);
      if (--left_ == 0) done_cv_.notify_all();
    }
  }

  PoseEngine& engine_;
  std::vector<std::thread> threads_;
  std::mutex mu_;
  std::condition_variable cv_, done_cv_;
  Chunk* chunk_ = nullptr;   // guarded by mu_
  std::size_t next_ = 0;     // guarded by mu_: the next task to claim
  std::size_t left_ = 0;     // guarded by mu_: tasks not finished
  uint64_t generation_ = 0;  // guarded by mu_
  bool stop_ = false;        // guarded by mu_
};

}  // namespace

ReplayResult run_replay_parallel(SampleSource& src, PipelineCore& core, const ReplayOptions& opt) {
  ReplayResult r;
  PoseEngine& engine = core.engine();
  const std::size_t sensors = core.sensors().size();
  bool first = true, calibration_pending = opt.calibrate_pose.has_value();
  const int64_t calibrate_after_ns = static_cast<int64_t>(opt.calibrate_at_s * 1e9);
  int64_t last_progress = 0;
  const uint64_t frames0 = core.last_frame().frame;
  // Read-ahead of one sample: a chunk that stops before the calibration request keeps it.
  ImuSample held;
  bool have_held = false, input_done = false;
  auto request_due = [&](const ImuSample& s) {
    return calibration_pending && s.t_host_ns - r.t_first_ns >= calibrate_after_ns;
  };
  // Fills c; prefilterable unless it starts at the calibration request (then it holds samples
  // up to the next request check only, taken one by one).
  auto read = [&](Chunk& c) {
    c.samples.clear();
    c.offsets.clear();
    c.offset_known.clear();
    c.prefiltered = false;
    c.ends_input = false;
    bool at_request = false;
    while (c.samples.size() < kChunkSamples) {
      ImuSample s;
      if (have_held) {
        s = held;
        have_held = false;
      } else if (input_done || !src.next(s)) {
        input_done = true;
        c.ends_input = true;
        break;
      }
      if (first) {
        r.t_first_ns = s.t_host_ns;
        first = false;
        if (opt.on_first_sample) opt.on_first_sample(s.t_host_ns);
      }
      if (request_due(s)) {
        if (!c.samples.empty()) {  // the chunk ends before it
          held = s;
          have_held = true;
          break;
        }
        at_request = true;
      }
      int64_t off = 0;
      const bool known = src.unix_offset_ns(off);
      c.samples.push_back(s);
      c.offsets.push_back(off);
      c.offset_known.push_back(known ? 1 : 0);
      if (at_request) break;  // the request's sample alone: taken one by one
    }
    return at_request;
  };
  // Per-sensor task lists; the chunk is prefilterable only if nothing can hand the filters
  // anything meanwhile (no capture, no countdown, no request in it).
  auto prepare = [&](Chunk& c, bool at_request) {
    c.by_sensor.resize(sensors);  // the lists keep their memory from chunk to chunk
    for (auto& list : c.by_sensor)
      list.clear();
    if (at_request || !engine.prefilter_allowed() || core.calibrating()) return false;
    c.outputs.resize(c.samples.size());
    for (std::size_t k = 0; k < c.samples.size(); ++k)
      if (core.accepts(c.samples[k]))
        c.by_sensor[c.samples[k].sensor_id].push_back(static_cast<uint32_t>(k));
    c.prefiltered = true;
    return true;
  };
  // The rest of the pipeline, in sample order (the sequential path for a chunk not
  // prefiltered, and while a capture runs).
  auto track = [&](Chunk& c) {
    for (std::size_t k = 0; k < c.samples.size() && !r.cancelled; ++k) {
      const ImuSample& s = c.samples[k];
      if (request_due(s)) {
        core.request_calibration(*opt.calibrate_pose, s.t_host_ns);
        calibration_pending = false;
      }
      if (c.offset_known[k]) core.set_unix_offset_ns(c.offsets[k]);
      core.advance_clock_to(s.t_host_ns);
      if (c.prefiltered && core.accepts(s))
        core.process(s, c.outputs[k]);
      else
        core.process(s);
      r.t_last_ns = s.t_host_ns;
      if ((++r.samples & 0x3FF) == 0) {
        if (opt.cancelled && opt.cancelled()) r.cancelled = true;
        const int64_t now = monotonic_ns();
        if (opt.progress && now - last_progress > 100'000'000) {
          opt.progress(src.progress());
          last_progress = now;
        }
      }
    }
  };
  {
    FilterPool pool(engine, opt.filter_threads);
    Chunk chunks[2];
    Chunk* cur = &chunks[0];
    Chunk* next = &chunks[1];
    if (prepare(*cur, read(*cur))) {
      pool.start(*cur);
      pool.help_and_wait();
    }
    while (!cur->samples.empty() && !r.cancelled) {
      // The next chunk's filters run while this one goes through the pipeline, but only when
      // this one cannot start a capture (it was prefiltered: no request in it).
      const bool at_request = read(*next);
      const bool overlap = cur->prefiltered && prepare(*next, at_request);
      if (overlap) pool.start(*next);
      track(*cur);
      if (overlap) {
        pool.help_and_wait();
      } else if (prepare(*next, at_request)) {  // the capture is over: prefilter again
        pool.start(*next);
        pool.help_and_wait();
      }
      std::swap(cur, next);
    }
  }
  if (!src.error().empty()) throw std::runtime_error(src.error());
  if (opt.progress) opt.progress(1.0);
  r.frames = core.last_frame().frame - frames0;
  return r;
}

}  // namespace mocap::daemon
