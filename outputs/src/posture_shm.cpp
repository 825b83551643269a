// Seqlock-protected shared-memory posture.
#include "mocap/outputs/posture_shm.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <stdexcept>

namespace mocap::outputs {
namespace {

constexpr uint64_t kMagic = 0x4d4f434150505331ull;  // "MOCAPPS1"
constexpr uint32_t kVersion = 1;
constexpr std::size_t kWords = sizeof(PoseFrame) / 8;

struct Header {
  uint64_t magic;
  uint32_t version;
  uint32_t frame_bytes;
  uint64_t seq;  // accessed through std::atomic_ref
  uint64_t pad;
};

struct ShmLayout {
  Header header;
  uint64_t words[kWords];
};
constexpr std::size_t kMapBytes = sizeof(ShmLayout);

}  // namespace

std::string default_posture_shm_name() {
  return "/mocap-posture-" + std::to_string(getuid());
}

PostureWriter::PostureWriter(std::string name) : name_(std::move(name)) {
  int fd = shm_open(name_.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0600);
  if (fd < 0) throw std::runtime_error("shm_open " + name_ + ": " + std::strerror(errno));
  if (ftruncate(fd, kMapBytes) != 0) {
    close(fd);
    throw std::runtime_error("ftruncate " + name_ + ": " + std::strerror(errno));
  }
  map_ = mmap(nullptr, kMapBytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  if (map_ == MAP_FAILED) throw std::runtime_error("mmap " + name_ + ": " + std::strerror(errno));
  auto* s = static_cast<ShmLayout*>(map_);
  std::atomic_ref<uint64_t>(s->header.seq).store(0, std::memory_order_relaxed);
  s->header.version = kVersion;
  s->header.frame_bytes = sizeof(PoseFrame);
  std::atomic_ref<uint64_t>(s->header.magic).store(kMagic, std::memory_order_release);
}

PostureWriter::~PostureWriter() {
  if (map_ && map_ != MAP_FAILED) munmap(map_, kMapBytes);
  shm_unlink(name_.c_str());
}

void PostureWriter::publish(const PoseFrame& frame) noexcept {
  auto* s = static_cast<ShmLayout*>(map_);
  std::atomic_ref<uint64_t> seq(s->header.seq);
  const uint64_t start = seq.load(std::memory_order_relaxed);
  seq.store(start + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  uint64_t src[kWords];
  std::memcpy(src, &frame, sizeof frame);
  for (std::size_t i = 0; i < kWords; ++i)
    std::atomic_ref<uint64_t>(s->words[i]).store(src[i], std::memory_order_relaxed);
  seq.store(start + 2, std::memory_order_release);
}

PostureReader::PostureReader(std::string name) : name_(std::move(name)) {
  int fd = shm_open(name_.c_str(), O_RDONLY | O_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("no shared posture " + name_ + ": " + std::strerror(errno));
  struct stat st {};
  if (fstat(fd, &st) != 0 || static_cast<std::size_t>(st.st_size) < kMapBytes) {
    close(fd);
    throw std::runtime_error("shared posture " + name_ + " has the wrong size");
  }
  map_ = mmap(nullptr, kMapBytes, PROT_READ, MAP_SHARED, fd, 0);
  close(fd);
  if (map_ == MAP_FAILED) throw std::runtime_error("mmap " + name_ + ": " + std::strerror(errno));
  auto* s = static_cast<const ShmLayout*>(map_);
  if (s->header.magic != kMagic || s->header.version != kVersion ||
      s->header.frame_bytes != sizeof(PoseFrame)) {
    munmap(const_cast<void*>(map_), kMapBytes);
    map_ = nullptr;
    throw std::runtime_error("shared posture " + name_ + " has an incompatible layout");
  }
}

PostureReader::~PostureReader() {
  if (map_ && map_ != MAP_FAILED) munmap(const_cast<void*>(map_), kMapBytes);
}

uint64_t PostureReader::sequence() const noexcept {
  auto* s = const_cast<ShmLayout*>(static_cast<const ShmLayout*>(map_));
  return std::atomic_ref<uint64_t>(s->header.seq).load(std::memory_order_acquire);
}

bool PostureReader::read(PoseFrame& out) const noexcept {
  auto* s = const_cast<ShmLayout*>(static_cast<const ShmLayout*>(map_));
  std::atomic_ref<uint64_t> seq(s->header.seq);
  uint64_t dst[kWords];
  for (int attempt = 0; attempt < 64; ++attempt) {
    const uint64_t before = seq.load(std::memory_order_acquire);
    if (before == 0) return false;  // nothing published yet
    if (before & 1) continue;
    for (std::size_t i = 0; i < kWords; ++i)
      dst[i] = std::atomic_ref<uint64_t>(s->words[i]).load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (seq.load(std::memory_order_relaxed) == before) {
      std::memcpy(&out, dst, sizeof out);
      return true;
    }
  }
  return false;
}

}  // namespace mocap::outputs
