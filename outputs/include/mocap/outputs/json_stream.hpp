// The pose JSON stream output: every PoseFrame as one line of JSON over TCP (or a private Unix
// socket) to any number of clients (schema in docs/streaming.md). on_frame()/publish() run on the
// pipeline thread: the frame is formatted once into a preallocated slot and handed to an I/O
// thread that serves non-blocking sockets under poll(); slow clients skip frames, the pipeline
// never blocks. When max_clients are connected, a new client takes the place of one that does not
// read (its kernel buffer full for 0.5 s, the longest first; else the most unsent bytes, at least
// 128 KiB), else it is closed. When the process runs out of file descriptors, a reserve fd is
// given up to accept and close the connection, and accepting pauses for 100 ms (never a busy loop).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "mocap/core/wakeup.hpp"
#include "mocap/outputs/output.hpp"
#include "mocap/outputs/outputs_config.hpp"
#include "mocap/outputs/pose_json.hpp"
#include "mocap/outputs/registry.hpp"

namespace mocap::outputs {

class PoseJsonServer final : public Output {
 public:
  struct Options {
    std::string bind_address = "127.0.0.1";  ///< IPv4 address to listen on (loopback default)
    uint16_t port = 0;                       ///< 0 = pick a free port (see port())
    /// Non-empty: listen on this Unix socket path instead of TCP, created mode 0600 (only this
    /// user can connect); an absolute path. A stale socket is replaced; a live one (another
    /// process listening) or any other file there is an error. Removed by stop().
    std::string unix_path;
    int max_clients = 32;  ///< further connections evict a stalled client or are closed at once
    std::size_t client_buffer_bytes = 256 * 1024;  ///< per-client queue of whole lines
    std::size_t max_client_input_bytes = 4096;     ///< a client sending more is dropped
    int realtime_priority = 0;  ///< SCHED_FIFO priority of the I/O thread (0 = normal)
  };
  struct Stats {
    uint64_t frames_published = 0;   ///< frames handed to the I/O thread
    uint64_t frames_dropped = 0;     ///< publish() found the hand-off full (I/O thread behind)
    uint64_t frames_skipped = 0;     ///< frame-to-client deliveries skipped (client buffer full)
    uint64_t clients_connected = 0;  ///< currently connected
    uint64_t clients_accepted = 0;   ///< ever accepted and served
    uint64_t clients_rejected = 0;   ///< closed at once because max_clients were connected
    uint64_t clients_dropped = 0;    ///< disconnected for sending too much input
    uint64_t clients_evicted = 0;    ///< disconnected to make room: not reading
    uint64_t bytes_sent = 0;
  };

  PoseJsonServer();
  ~PoseJsonServer() override;
  PoseJsonServer(const PoseJsonServer&) = delete;
  PoseJsonServer& operator=(const PoseJsonServer&) = delete;

  /// Binds, listens and starts the I/O thread. On failure returns false with a message
  /// naming the address and the system error.
  bool start(const Options& options, std::string* error);
  /// The TCP port actually listened on (after start(); 0 on a Unix socket).
  uint16_t port() const { return port_; }
  /// Pipeline thread (single producer): formats the frame and hands it over. Never blocks,
  /// never allocates. Returns false if the frame was dropped (hand-off full or not started).
  bool publish(const PoseFrame& frame) noexcept;
  void on_frame(const PoseFrame& frame) override { publish(frame); }
  Stats stats() const;
  /// Stops the I/O thread and closes every socket (also done by the destructor).
  void stop();

 private:
  /// Creates listen_fd_ on options_.unix_path (mode 0600); false with a message.
  bool listen_unix(std::string* error);
  /// Allocates the hand-off and client tables and starts the I/O thread.
  bool start_io();
  bool unix_bound_ = false;  ///< options_.unix_path is ours to remove
  struct Slot {
    std::size_t len = 0;
    char data[kPoseJsonMaxLine];
  };
  // Frames the I/O thread may fall behind before publish() drops one for every client: 64
  // frames (0.5 s at 120 Hz) ride out scheduling stalls of a loaded machine (8 did not: see
  // tests/reliability/test_clients.cpp).
  static constexpr std::size_t kSlots = 64;
  struct Client;
  struct Counters {
    std::atomic<uint64_t> published{0}, dropped{0}, skipped{0}, connected{0}, accepted{0},
        rejected{0}, abusive{0}, evicted{0}, bytes_sent{0};
  };

  void run();
  void deliver(const Slot& slot);
  bool flush(Client& c);
  void accept_clients();
  void remove_client(std::size_t i);

  Options options_;
  int listen_fd_ = -1;
  uint16_t port_ = 0;
  std::unique_ptr<Slot[]> slots_;
  alignas(64) std::atomic<uint64_t> head_{0};
  alignas(64) std::atomic<uint64_t> tail_{0};
  std::atomic<bool> stop_{false};
  Wakeup wakeup_;
  std::thread thread_;
  std::unique_ptr<std::unique_ptr<Client>[]> clients_;
  std::size_t client_count_ = 0;
  std::unique_ptr<char[]> scratch_;
  Counters counters_;
  int reserve_fd_ = -1;              ///< given up to shed a connection when out of fds
  int64_t accept_paused_until_ = 0;  ///< I/O thread: no accept before (fds exhausted)
};

/// The [outputs.json] output: a started PoseJsonServer (registry factory).
std::unique_ptr<Output> make_json_stream(const OutputsConfig& cfg, const OutputContext& ctx);

/// The TCP port the pose JSON stream among `outputs` listens on (the one picked when the
/// configured port is 0); 0 when there is none.
int json_stream_port(const std::vector<std::unique_ptr<Output>>& outputs);

}  // namespace mocap::outputs
