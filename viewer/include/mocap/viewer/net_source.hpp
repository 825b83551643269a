// A remote daemon's pose JSON stream (--connect HOST:PORT) as a pose source: a non-blocking TCP
// client that keeps the newest complete line, skips bad lines (counted, last error shown) and
// reconnects once a second after a failure. poll() never blocks the render loop.
#pragma once

#include <string>

#include "mocap/viewer/pose_source.hpp"

namespace mocap::viewer {

class NetSource final : public PoseSource {
 public:
  /// Throws std::runtime_error if `host_port` is not HOST:PORT.
  explicit NetSource(const std::string& host_port);
  ~NetSource() override;
  NetSource(const NetSource&) = delete;
  NetSource& operator=(const NetSource&) = delete;

  bool poll(double t_s, std::vector<PoseFrame>& frames) override;
  std::string status() const override;
  void set_paused(bool paused) override { paused_ = paused; }

  uint64_t bad_lines() const { return bad_lines_; }
  uint64_t good_lines() const { return good_lines_; }

 private:
  void disconnect(const std::string& why, double t_s);
  bool start_connect(double t_s);

  std::string host_, port_;
  int fd_ = -1;
  bool connected_ = false, paused_ = false;
  double next_try_s_ = 0, connect_deadline_s_ = 0;
  std::string buffer_, error_;
  uint64_t bad_lines_ = 0, good_lines_ = 0;
};

}  // namespace mocap::viewer
