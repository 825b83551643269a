// The shared posture output: an exclusive, private shared-memory object (ShmOwner) and the
// seqlock PostureWriter (posture_shm.hpp).
#include "mocap/outputs/posture_output.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "mocap/outputs/posture_shm.hpp"

namespace mocap::outputs {

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

class PostureOutput final : public Output {
 public:
  explicit PostureOutput(std::string name) : owner_(name), writer_(std::move(name)) {}
  void on_frame(const PoseFrame& f) override { writer_.publish(f); }

 private:
  ShmOwner owner_;  // declared first: locked before the writer exists, released after it
  PostureWriter writer_;
};

}  // namespace

std::unique_ptr<Output> make_posture(const OutputsConfig& cfg, const OutputContext& ctx) {
  const std::string name =
      cfg.posture.shm_name.empty() ? default_posture_shm_name() : cfg.posture.shm_name;
  auto out = std::make_unique<PostureOutput>(name);
  if (ctx.log) ctx.log->info("shared posture %s", name.c_str());
  return out;
}

}  // namespace mocap::outputs
