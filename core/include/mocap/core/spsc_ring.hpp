// Single-producer / single-consumer lock-free ring: the hand-off from a device reader thread to
// the pipeline thread. Fixed capacity, storage inline (slots are assigned, never constructed), so
// nothing is allocated per sample. A push into a full ring fails (the caller counts a drop) instead
// of blocking the device thread.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace mocap {

template <typename T, std::size_t Capacity>
class SpscRing {
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0,
                "capacity must be a power of two");
  static_assert(std::is_copy_assignable_v<T>, "ring elements are copied in place");

 public:
  static constexpr std::size_t kCapacity = Capacity;

  /// Producer side. Returns false (and leaves the ring unchanged) when full.
  bool try_push(const T& value) noexcept {
    const uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ >= Capacity) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ >= Capacity) return false;
    }
    slots_[head & (Capacity - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Consumer side. Returns false when empty.
  bool try_pop(T& out) noexcept {
    const uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    out = slots_[tail & (Capacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Approximate fill level; exact when called from either side while the other is idle.
  std::size_t size() const noexcept {
    return static_cast<std::size_t>(head_.load(std::memory_order_acquire) -
                                    tail_.load(std::memory_order_acquire));
  }
  bool empty() const noexcept { return size() == 0; }

 private:
  alignas(64) std::atomic<uint64_t> head_{0};  // next slot to write (producer-owned)
  uint64_t tail_cache_ = 0;                    // producer's last view of tail_
  alignas(64) std::atomic<uint64_t> tail_{0};  // next slot to read (consumer-owned)
  uint64_t head_cache_ = 0;                    // consumer's last view of head_
  alignas(64) std::array<T, Capacity> slots_{};
};

}  // namespace mocap
