// The SlimeVR server logic as a pure decoder (internal): addressed datagrams in, orientation
// samples per mapped (MAC, sensor id) out, plus the replies a server owes each tracker
// (handshake, sensor-info ack, feature flags, heartbeats, pings) queued for the device to send.
// Deterministic given its inputs, so recorded records replay through it bit for bit.
//
// Record = what the device reads and records: [u32 IPv4][u16 port] (big-endian, the tracker's
// address) then the datagram.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "decoder_common.hpp"
#include "mocap/drivers/slimevr.hpp"

namespace mocap {

constexpr std::size_t kSlimeRecordHeader = 6;

/// One tracker sensor of the rig: a board's MAC and the sensor id on it.
struct SlimeMapping {
  slimevr::Mac mac{};
  uint8_t tracker_sensor = 0;
  uint16_t sensor_id = 0;  ///< rig sensor index stamped on samples (and used as device index)
  std::string axis_remap;  ///< this sensor's own (a group's members differ); "" = the spec's
};

/// The mapping from spec.options: "trackers" = "MAC/ID=INDEX[@AXIS_REMAP];..." (a group of rig
/// sensors on one port), else "mac" (+ "tracker", default 0) for this one sensor. Throws
/// invalid_argument.
std::vector<SlimeMapping> slime_mappings(const DeviceSpec& spec);

/// Sets field to `name` (from a SlimeVR id table), or to "WHAT N" for an id it does not know.
template <std::size_t N>
void set_named(char (&field)[N], const char* name, const char* what, uint32_t id) {
  char buf[32];
  if (name == nullptr) std::snprintf(buf, sizeof buf, "%s %u", what, id);
  SensorTelemetry::set(field, name ? name : buf);
}

/// A board that sent a handshake (for status and `mocap devices`).
struct SlimeBoardInfo {
  uint32_t ip = 0;
  uint16_t port = 0;
  slimevr::Mac mac{};
  uint32_t board = 0, imu = 0, mcu = 0, protocol_version = 0;
  std::string firmware;
};

class SlimeVrDecoder final : public ProtocolDecoder {
 public:
  explicit SlimeVrDecoder(const DeviceSpec& spec);
  void feed(std::span<const uint8_t> record, int64_t t_host_ns, SampleSink& sink) override;
  const DecoderStats& stats() const override { return stats_; }
  uint64_t replies(uint32_t type) const override;

  /// Keep-alive: heartbeats every 0.5 s and pings every 1 s to each known board; a board
  /// silent for timeout_ns is forgotten and its sensors reported disconnected. A resting
  /// tracker sends no rotations (the firmware sends only changes) while it still answers: its
  /// orientation is repeated every 100 ms (kFlagInterpolated) so it is not taken as stale, as
  /// long as its board was heard within the last second.
  void tick(int64_t t_host_ns, SampleSink& sink);

  struct Reply {
    uint32_t ip = 0;
    uint16_t port = 0;
    uint8_t len = 0;
    std::array<uint8_t, 64> bytes{};
  };
  /// Replies queued since the last take (the device sends them, then calls clear_replies).
  std::span<const Reply> pending_replies() const { return {replies_.data(), n_replies_}; }
  void clear_replies() { n_replies_ = 0; }
  std::vector<SlimeBoardInfo> boards() const;
  std::size_t board_count() const;  ///< boards that said hello (no allocation)
  /// Calls f(record) with each known board's handshake record as it arrived (address
  /// included). The device records them again now and then, so a recording started after the
  /// boards connected still names them when its raw datagrams replay through this decoder.
  template <class F>
  void each_hello_record(F&& f) const {
    for (const Board& b : boards_)
      if (b.used && b.hello && b.hello_len > 0) f(std::span(b.hello_record.data(), b.hello_len));
  }
  int64_t timeout_ns = 3'000'000'000;

 private:
  static constexpr std::size_t kMaxBoards = 64;
  struct Board {
    bool used = false, hello = false;
    uint32_t ip = 0;
    uint16_t port = 0;
    slimevr::Mac mac{};
    uint32_t board = 0, imu = 0, mcu = 0, protocol_version = 0;
    std::array<char, 64> firmware{};
    uint8_t firmware_len = 0;
    uint64_t last_number = 0;
    int64_t last_heard_ns = 0, last_heartbeat_ns = 0, last_ping_ns = 0;
    uint64_t heartbeat_number = 0;
    std::array<uint8_t, 256> hello_record{};
    std::size_t hello_len = 0;
  };
  struct Sensor {
    SlimeMapping map;
    DecoderCommon common;
    int board = -1;  ///< index in boards_ while connected
    bool new_quat = false, has_acc = false, connected = false;
    int64_t last_emit_ns = 0;
    uint32_t number = 0;  ///< packet number of the datagram with its newest rotation (0: none)
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    Eigen::Vector3d lin_acc_m_s2 = Eigen::Vector3d::Zero();
    SensorTelemetry telemetry;  ///< what its board said of itself and of this sensor
    bool telemetry_changed = false;
  };

  int board_for(uint32_t ip, uint16_t port, int64_t t_ns);
  void handle(int b, const slimevr::Packet& p, int64_t t_ns, SampleSink& sink);
  void queue(const Board& b, std::span<const uint8_t> bytes);
  /// number: the carrying datagram's packet number (0: none, or a hold of the last rotation).
  void emit(Sensor& s, int64_t t_ns, SampleSink& sink, uint8_t flags = 0, uint64_t number = 0);
  /// Applies f to the telemetry of the rig sensors on board bi (all of them, or only those with
  /// tracker sensor id `only` when it is 0..254), noting which changed.
  template <class F>
  void update_telemetry(int bi, int only, F&& f);

  DecoderStats stats_;
  std::array<Board, kMaxBoards> boards_{};
  std::vector<Sensor> sensors_;  // sized once in the constructor
  std::array<slimevr::Packet, slimevr::kMaxPackets> packets_{};
  std::array<Reply, 64> replies_{};
  std::size_t n_replies_ = 0;
  std::array<uint64_t, 256> reply_count_{};  // per packet type received (replies())
  int32_t next_ping_id_ = 1;
};

}  // namespace mocap
