// One request line, one reply line over a Unix stream socket (unix_line_client.hpp).
#include "mocap/core/unix_line_client.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "mocap/core/time.hpp"

namespace mocap {
namespace {

struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

constexpr std::size_t kMaxReplyBytes = 1u << 24;

}  // namespace

std::string unix_line_call(const std::string& path, std::string_view request_line, int timeout_ms,
                           std::string_view peer_name) {
  const std::string peer(peer_name);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if (path.size() >= sizeof a.sun_path)
    throw std::runtime_error("control socket path too long: " + path);
  std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
  Fd s{::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0)};
  if (s.fd < 0 || ::connect(s.fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0)
    throw std::runtime_error("cannot reach " + peer + " at " + path + ": " + std::strerror(errno) +
                             " (is it running?)");
  ucred cred{};
  socklen_t cred_len = sizeof cred;
  if (::getsockopt(s.fd, SOL_SOCKET, SO_PEERCRED, &cred, &cred_len) != 0 ||
      (cred.uid != ::geteuid() && cred.uid != 0))
    throw std::runtime_error("refusing " + path + ": it is served by uid " +
                             std::to_string(cred.uid) + " (pid " + std::to_string(cred.pid) +
                             "), not by us (uid " + std::to_string(::geteuid()) +
                             "); another user's process, not our " + peer);
  std::string line(request_line);
  if (line.empty() || line.back() != '\n') line += '\n';
  for (std::string_view rest = line; !rest.empty();) {
    const ssize_t n = ::send(s.fd, rest.data(), rest.size(), MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error("cannot send to " + peer + " at " + path);
    rest.remove_prefix(static_cast<size_t>(n));
  }
  std::string reply;
  char buf[4096];
  const int64_t deadline = monotonic_ns() + static_cast<int64_t>(timeout_ms) * 1000000;
  while (reply.find('\n') == std::string::npos && reply.size() <= kMaxReplyBytes) {
    const int64_t left_ms = (deadline - monotonic_ns()) / 1000000;
    pollfd p{s.fd, POLLIN, 0};
    if (left_ms <= 0 || ::poll(&p, 1, static_cast<int>(left_ms)) <= 0)
      throw std::runtime_error(peer + " did not answer within " + std::to_string(timeout_ms) +
                               " ms");
    const ssize_t n = ::recv(s.fd, buf, sizeof buf, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    reply.append(buf, static_cast<size_t>(n));
  }
  if (const size_t nl = reply.find('\n'); nl != std::string::npos) reply.resize(nl);
  while (!reply.empty() && reply.back() == '\r')
    reply.pop_back();
  return reply;
}

}  // namespace mocap
