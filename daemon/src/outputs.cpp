// Builds the configured frame outputs: posture shared memory, JSON/TCP stream, VMC/OSC and VRChat
// OSC senders.
#include "mocap/daemon/outputs.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "mocap/daemon/json_stream.hpp"
#include "mocap/daemon/vmc.hpp"
#include "mocap/daemon/vrchat.hpp"
#include "mocap/skeleton/posture_shm.hpp"

namespace mocap::daemon {

namespace {

/// Holds an exclusive flock on the shared-memory object for the daemon's life: a second mocapd
/// publishing under the same name is refused before it creates (or, on exit, removes) anything.
class ShmOwner {
 public:
  explicit ShmOwner(const std::string& name) {
    // Created exclusively when it does not exist; an existing one (left by a crash) is reused
    // only if it is ours and private: another user could have created it to read our poses.
    fd_ = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd_ < 0 && errno == EEXIST) fd_ = ::shm_open(name.c_str(), O_RDWR | O_CLOEXEC, 0600);
    if (fd_ < 0) throw std::runtime_error("shm_open " + name + ": " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || st.st_uid != ::geteuid() || (st.st_mode & 077) != 0) {
      ::close(fd_);
      throw std::runtime_error("shared posture " + name + " exists and is not private to us " +
                               "(owner uid " + std::to_string(st.st_uid) + ", mode 0" +
                               [&] {
                                 char b[8];
                                 std::snprintf(b, sizeof b, "%o", st.st_mode & 0777);
                                 return std::string(b);
                               }() +
                               "): refused (left untouched)");
    }
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw std::runtime_error("shared posture " + name +
                               " is in use by another mocapd (left untouched)");
    }
  }
  ~ShmOwner() { ::close(fd_); }  // after the writer has removed the object
  ShmOwner(const ShmOwner&) = delete;
  ShmOwner& operator=(const ShmOwner&) = delete;

 private:
  int fd_ = -1;
};

class PostureSink final : public FrameSink {
 public:
  explicit PostureSink(std::string name) : owner_(name), writer_(std::move(name)) {}
  void publish(const PoseFrame& f) override { writer_.publish(f); }

 private:
  ShmOwner owner_;  // declared first: locked before the writer exists, released after it
  PostureWriter writer_;
};

class JsonSink final : public FrameSink {
 public:
  JsonSink(const JsonOutputConfig& c, int realtime_priority, Logger& log) {
    PoseJsonServer::Options o;
    o.realtime_priority = realtime_priority;
    o.bind_address = c.bind;
    o.port = static_cast<uint16_t>(c.port);
    o.max_clients = c.max_clients;
    o.unix_path = c.unix_socket;
    std::string err;
    if (!server_.start(o, &err)) throw std::runtime_error("outputs.json: " + err);
    if (c.unix_socket.empty())
      log.info("pose JSON stream on %s:%u", c.bind.c_str(), server_.port());
    else
      log.info("pose JSON stream on Unix socket %s (mode 0600)", c.unix_socket.c_str());
  }
  void publish(const PoseFrame& f) override { server_.publish(f); }
  uint16_t port() const { return server_.port(); }

 private:
  PoseJsonServer server_;
};

class VmcSink final : public FrameSink {
 public:
  VmcSink(const VmcOutputConfig& c, Logger& log) {
    VmcSender::Options o;
    o.host = c.host;
    o.port = static_cast<uint16_t>(c.port);
    std::string err;
    if (!sender_.open(o, &err)) throw std::runtime_error("outputs.vmc: " + err);
    log.info("VMC to %s:%d", c.host.c_str(), c.port);
  }
  void publish(const PoseFrame& f) override { sender_.publish(f); }

 private:
  VmcSender sender_;
};

class VrchatSink final : public FrameSink {
 public:
  VrchatSink(const VrchatOutputConfig& c, double model_height_m, Logger& log) {
    VrchatSender::Options o;
    o.host = c.host;
    o.port = static_cast<uint16_t>(c.port);
    o.slots.fill(-1);
    for (std::size_t i = 0; i < c.trackers.size() && i < o.slots.size(); ++i)
      if (const auto s = segment_from_name(c.trackers[i])) o.slots[i] = index(*s);
    o.head = c.head;
    o.scale = c.height_m > 0 && model_height_m > 0 ? c.height_m / model_height_m : 1.0;
    std::string err;
    if (!sender_.open(o, &err)) throw std::runtime_error("outputs.vrchat: " + err);
    log.info("VRChat OSC trackers to %s:%d (position scale %.3f)", c.host.c_str(), c.port, o.scale);
  }
  void publish(const PoseFrame& f) override { sender_.publish(f); }

 private:
  VrchatSender sender_;
};

}  // namespace

std::vector<std::unique_ptr<FrameSink>> make_outputs(const Config& cfg, Logger& log) {
  std::vector<std::unique_ptr<FrameSink>> out;
  if (cfg.outputs.posture.enabled) {
    const std::string name = cfg.outputs.posture.shm_name.empty() ? default_posture_shm_name()
                                                                  : cfg.outputs.posture.shm_name;
    try {
      out.push_back(std::make_unique<PostureSink>(name));
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string("outputs.posture: ") + e.what());
    }
    log.info("shared posture %s", name.c_str());
  }
  if (cfg.outputs.json.enabled)
    out.push_back(
        std::make_unique<JsonSink>(cfg.outputs.json, cfg.pipeline.realtime_priority, log));
  if (cfg.outputs.vmc.enabled) out.push_back(std::make_unique<VmcSink>(cfg.outputs.vmc, log));
  if (cfg.outputs.vrchat.enabled)
    out.push_back(std::make_unique<VrchatSink>(cfg.outputs.vrchat, cfg.body.model.height_m, log));
  return out;
}

int json_stream_port(const std::vector<std::unique_ptr<FrameSink>>& outputs) {
  for (const auto& o : outputs)
    if (const auto* j = dynamic_cast<const JsonSink*>(o.get())) return j->port();
  return 0;
}

}  // namespace mocap::daemon
