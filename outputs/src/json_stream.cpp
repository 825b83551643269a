// PoseJsonServer: TCP (or private Unix socket) listener and I/O thread for the pose JSON stream.
// The pipeline hands formatted lines over through a fixed ring of slots; the I/O thread copies each
// line into every client's bounded queue (or skips it for that client) and writes with non-blocking
// sockets.
#include "mocap/outputs/json_stream.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <linux/sockios.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "mocap/core/thread_priority.hpp"
#include "mocap/core/time.hpp"

namespace mocap::outputs {

/// One connected client: a byte ring holding whole queued lines.
struct PoseJsonServer::Client {
  int fd = -1;
  std::vector<char> ring;  // allocated once at accept
  std::size_t read_pos = 0;
  std::size_t used = 0;
  std::size_t input_bytes = 0;
  int64_t stalled_since_ns = 0;  // first time its queue could not be sent on (0: keeping up)

  std::size_t free_bytes() const { return ring.size() - used; }
  void push(const char* data, std::size_t len) {
    std::size_t w = (read_pos + used) % ring.size();
    const std::size_t first = std::min(len, ring.size() - w);
    std::memcpy(ring.data() + w, data, first);
    std::memcpy(ring.data(), data + first, len - first);
    used += len;
  }
};

PoseJsonServer::PoseJsonServer() = default;

PoseJsonServer::~PoseJsonServer() {
  stop();
}

bool PoseJsonServer::start(const Options& options, std::string* error) {
  auto fail = [&](const std::string& what) {
    if (error)
      *error = "pose stream: " + what + " " + options.bind_address + ":" +
               std::to_string(options.port) + ": " + std::strerror(errno);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    listen_fd_ = -1;
    return false;
  };
  if (thread_.joinable()) {
    if (error) *error = "pose stream: already started";
    return false;
  }
  if (options.max_clients < 1 || options.client_buffer_bytes < kPoseJsonMaxLine) {
    if (error) *error = "pose stream: max_clients must be >= 1 and client buffer >= 16 KiB";
    return false;
  }
  options_ = options;
  if (!options.unix_path.empty()) {
    if (!listen_unix(error)) return false;
    port_ = 0;
    return start_io();
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(options.port);
  if (inet_pton(AF_INET, options.bind_address.c_str(), &addr.sin_addr) != 1) {
    if (error) *error = "pose stream: bind address '" + options.bind_address + "' is not IPv4";
    return false;
  }
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) return fail("socket");
  int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
    return fail("cannot bind");
  if (::listen(listen_fd_, 16) != 0) return fail("cannot listen on");
  socklen_t len = sizeof addr;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  return start_io();
}

bool PoseJsonServer::listen_unix(std::string* error) {
  const std::string& path = options_.unix_path;
  auto fail = [&](const std::string& why) {
    if (error) *error = "pose stream: Unix socket '" + path + "': " + why;
    if (listen_fd_ >= 0) ::close(listen_fd_);
    listen_fd_ = -1;
    return false;
  };
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if (path.front() != '/') return fail("not an absolute path");
  if (path.size() >= sizeof a.sun_path)
    return fail("longer than " + std::to_string(sizeof a.sun_path - 1) + " bytes");
  std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0) {
    if (!S_ISSOCK(st.st_mode)) return fail("exists and is not a socket (left untouched)");
    const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    const bool live =
        probe >= 0 && ::connect(probe, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
    if (probe >= 0) ::close(probe);
    if (live) return fail("another process is listening on it");
    ::unlink(path.c_str());  // stale socket of a daemon that died
  }
  listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) return fail(std::string("socket(): ") + std::strerror(errno));
  const mode_t old = ::umask(0177);  // created 0600: only this user can connect
  const int rc = ::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a);
  const int bind_errno = errno;
  ::umask(old);
  if (rc != 0) return fail(std::strerror(bind_errno));
  if (::chmod(path.c_str(), 0600) != 0 || ::listen(listen_fd_, 16) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(path.c_str());
    return fail(why);
  }
  unix_bound_ = true;
  return true;
}

bool PoseJsonServer::start_io() {
  slots_ = std::make_unique<Slot[]>(kSlots);
  clients_ = std::make_unique<std::unique_ptr<Client>[]>(options_.max_clients);
  scratch_ = std::make_unique<char[]>(4096);
  client_count_ = 0;
  stop_.store(false);
  thread_ = std::thread([this] { run(); });
  return true;
}

bool PoseJsonServer::publish(const PoseFrame& frame) noexcept {
  if (!slots_ || !thread_.joinable()) return false;
  const uint64_t head = head_.load(std::memory_order_relaxed);
  if (head - tail_.load(std::memory_order_acquire) >= kSlots) {
    counters_.dropped.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  Slot& slot = slots_[head % kSlots];
  slot.len = format_pose_json(frame, slot.data, sizeof slot.data);
  head_.store(head + 1, std::memory_order_release);
  counters_.published.fetch_add(1, std::memory_order_relaxed);
  wakeup_.notify();
  return true;
}

PoseJsonServer::Stats PoseJsonServer::stats() const {
  Stats s;
  s.frames_published = counters_.published.load();
  s.frames_dropped = counters_.dropped.load();
  s.frames_skipped = counters_.skipped.load();
  s.clients_connected = counters_.connected.load();
  s.clients_accepted = counters_.accepted.load();
  s.clients_rejected = counters_.rejected.load();
  s.clients_dropped = counters_.abusive.load();
  s.clients_evicted = counters_.evicted.load();
  s.bytes_sent = counters_.bytes_sent.load();
  return s;
}

void PoseJsonServer::stop() {
  if (thread_.joinable()) {
    stop_.store(true);
    wakeup_.notify();
    thread_.join();
  }
  for (std::size_t i = client_count_; i > 0; --i)
    remove_client(i - 1);
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
  if (reserve_fd_ >= 0) ::close(reserve_fd_);
  reserve_fd_ = -1;
  if (unix_bound_) ::unlink(options_.unix_path.c_str());
  unix_bound_ = false;
}

void PoseJsonServer::remove_client(std::size_t i) {
  ::close(clients_[i]->fd);
  clients_[i] = std::move(clients_[client_count_ - 1]);
  --client_count_;
  counters_.connected.store(client_count_);
}

void PoseJsonServer::accept_clients() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EMFILE || errno == ENFILE) {
        // Out of fds: the pending connection would keep the listener readable forever. Give up
        // the reserve fd to take it and close it, take the reserve back, and pause accepting.
        if (reserve_fd_ >= 0) {
          ::close(reserve_fd_);
          const int shed = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
          if (shed >= 0) {
            ::close(shed);
            counters_.rejected.fetch_add(1);
          }
          reserve_fd_ = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
        }
        accept_paused_until_ = monotonic_ns() + 100'000'000;
      }
      return;  // EAGAIN, or a transient error: poll again
    }
    if (client_count_ >= static_cast<std::size_t>(options_.max_clients)) {
      // Full: a client that does not read makes room: the one stalled longest (its kernel
      // buffer full for at least 0.5 s), else the one with the most unsent bytes if that is
      // at least 128 KiB (a reading client has next to none).
      const int64_t now = monotonic_ns();
      std::size_t victim = client_count_;
      for (std::size_t i = 0; i < client_count_; ++i) {
        const Client& c = *clients_[i];
        if (c.stalled_since_ns == 0 || now - c.stalled_since_ns < 500'000'000) continue;
        if (victim == client_count_ || c.stalled_since_ns < clients_[victim]->stalled_since_ns)
          victim = i;
      }
      if (victim == client_count_) {
        std::size_t most = 128 * 1024;
        for (std::size_t i = 0; i < client_count_; ++i) {
          int unsent = 0;
          if (::ioctl(clients_[i]->fd, SIOCOUTQ, &unsent) != 0) unsent = 0;
          const std::size_t backlog =
              static_cast<std::size_t>(std::max(unsent, 0)) + clients_[i]->used;
          if (backlog >= most) {
            most = backlog;
            victim = i;
          }
        }
      }
      if (victim == client_count_) {
        ::close(fd);
        counters_.rejected.fetch_add(1);
        continue;
      }
      remove_client(victim);
      counters_.evicted.fetch_add(1);
    }
    int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    auto c = std::make_unique<Client>();
    c->fd = fd;
    c->ring.resize(options_.client_buffer_bytes);
    clients_[client_count_++] = std::move(c);
    counters_.accepted.fetch_add(1);
    counters_.connected.store(client_count_);
  }
}

void PoseJsonServer::deliver(const Slot& slot) {
  if (slot.len == 0) return;
  for (std::size_t i = 0; i < client_count_; ++i) {
    Client& c = *clients_[i];
    if (c.free_bytes() < slot.len) {
      counters_.skipped.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    c.push(slot.data, slot.len);
  }
}

bool PoseJsonServer::flush(Client& c) {
  while (c.used > 0) {
    const std::size_t first = std::min(c.used, c.ring.size() - c.read_pos);
    const ssize_t n = ::send(c.fd, c.ring.data() + c.read_pos, first, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) {
        if (c.stalled_since_ns == 0) c.stalled_since_ns = monotonic_ns();
        return true;
      }
      if (errno == EINTR) continue;
      return false;  // EPIPE, ECONNRESET: the client is gone
    }
    c.read_pos = (c.read_pos + static_cast<std::size_t>(n)) % c.ring.size();
    c.used -= static_cast<std::size_t>(n);
    counters_.bytes_sent.fetch_add(static_cast<uint64_t>(n), std::memory_order_relaxed);
  }
  c.stalled_since_ns = 0;  // everything sent: keeping up
  return true;
}

void PoseJsonServer::run() {
  // Not granted: the pipeline thread has already warned with the same reason.
  (void)set_this_thread_realtime(options_.realtime_priority, nullptr);
  const std::size_t max_fds = static_cast<std::size_t>(options_.max_clients) + 2;
  std::vector<pollfd> fds(max_fds);  // allocated once for the thread's life
  reserve_fd_ = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  while (!stop_.load()) {
    const int64_t pause_ns = accept_paused_until_ - monotonic_ns();
    fds[0] = {wakeup_.fd(), POLLIN, 0};
    fds[1] = {pause_ns > 0 ? -1 : listen_fd_, POLLIN, 0};
    for (std::size_t i = 0; i < client_count_; ++i) {
      const Client& c = *clients_[i];
      fds[i + 2] = {c.fd, static_cast<short>(POLLIN | (c.used ? POLLOUT : 0)), 0};
    }
    const std::size_t nfds = client_count_ + 2;
    const int r =
        ::poll(fds.data(), nfds, pause_ns > 0 ? static_cast<int>(pause_ns / 1'000'000 + 1) : 500);
    if (r < 0 && errno != EINTR) break;
    if (stop_.load()) break;

    // Clients first (indices match fds as built above); iterate backwards so removal by
    // swapping with the last client does not disturb the ones not yet visited.
    for (std::size_t i = nfds - 2; i > 0; --i) {
      const std::size_t ci = i - 1;
      const short re = fds[ci + 2].revents;
      if (!re) continue;
      Client& c = *clients_[ci];
      bool keep = true;
      if (re & POLLIN) {
        const ssize_t n = ::recv(c.fd, scratch_.get(), 4096, MSG_DONTWAIT);
        if (n == 0) {
          keep = false;  // orderly shutdown by the client
        } else if (n > 0) {
          c.input_bytes += static_cast<std::size_t>(n);
          if (c.input_bytes > options_.max_client_input_bytes) {
            keep = false;
            counters_.abusive.fetch_add(1);
          }
        } else if (errno != EAGAIN && errno != EINTR) {
          keep = false;
        }
      }
      if (keep && (re & (POLLERR | POLLHUP | POLLNVAL))) keep = false;
      if (keep && (re & POLLOUT)) keep = flush(c);
      if (!keep) remove_client(ci);
    }
    if (fds[1].fd >= 0 && (fds[1].revents & POLLIN)) accept_clients();
    if (fds[0].revents & POLLIN) wakeup_.wait(0);

    uint64_t tail = tail_.load(std::memory_order_relaxed);
    const uint64_t head = head_.load(std::memory_order_acquire);
    if (tail != head) {
      for (; tail != head; ++tail)
        deliver(slots_[tail % kSlots]);
      tail_.store(tail, std::memory_order_release);
      for (std::size_t i = client_count_; i > 0; --i)
        if (!flush(*clients_[i - 1])) remove_client(i - 1);
    }
  }
}

std::unique_ptr<Output> make_json_stream(const OutputsConfig& cfg, const OutputContext& ctx) {
  const JsonOutputConfig& c = cfg.json;
  PoseJsonServer::Options o;
  o.realtime_priority = ctx.realtime_priority;
  o.bind_address = c.bind;
  o.port = static_cast<uint16_t>(c.port);
  o.max_clients = c.max_clients;
  o.unix_path = c.unix_socket;
  auto server = std::make_unique<PoseJsonServer>();
  std::string err;
  if (!server->start(o, &err)) throw std::runtime_error(err);
  if (ctx.log) {
    if (c.unix_socket.empty())
      ctx.log->info("pose JSON stream on %s:%u", c.bind.c_str(), server->port());
    else
      ctx.log->info("pose JSON stream on Unix socket %s (mode 0600)", c.unix_socket.c_str());
  }
  return server;
}

int json_stream_port(const std::vector<std::unique_ptr<Output>>& outputs) {
  for (const auto& o : outputs)
    if (const auto* j = dynamic_cast<const PoseJsonServer*>(o.get())) return j->port();
  return 0;
}

}  // namespace mocap::outputs
