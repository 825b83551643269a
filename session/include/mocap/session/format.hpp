// The session file format (docs/session-format.md): constants, limits, the header record, and
// the explicit little-endian encoding of each block payload (raw bytes, ImuSample, PoseFrame).
// Shared by SessionWriter and SessionReader; no I/O here.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::session {

inline constexpr char kMagic[8] = {'M', 'O', 'C', 'A', 'P', 'S', 'E', 'S'};
inline constexpr uint32_t kVersion = 1;
inline constexpr uint32_t kEndianTag = 0x01020304u;  ///< reads back as 04 03 02 01 on disk
inline constexpr uint16_t kBlockSync = 0xB10Cu;      ///< first two bytes of every block

// Limits: every length field is checked against these before anything is allocated.
inline constexpr std::size_t kMaxTextBytes = 1u << 20;    ///< config / calibration text
inline constexpr std::size_t kMaxHeaderBytes = 4u << 20;  ///< whole header payload
inline constexpr std::size_t kMaxSensorEntries = 256;     ///< sensor descriptions
inline constexpr std::size_t kMaxNameBytes = 255;         ///< sensor name / protocol
inline constexpr std::size_t kMaxRawChunk = 64u * 1024;   ///< raw bytes per block
inline constexpr std::size_t kBlockHeaderBytes = 8;       ///< sync, type, reserved, length
inline constexpr std::size_t kBlockTrailerBytes = 4;      ///< CRC32
inline constexpr std::size_t kRawPrefixBytes = 12;        ///< device index, pad, t_host_ns
inline constexpr std::size_t kSamplePayloadBytes = 128;
inline constexpr std::size_t kPoseFixedBytes = 32 + 52 * kSegmentCount;
inline constexpr std::size_t kPoseSensorBytes = 52;
inline constexpr std::size_t kMaxPosePayload = kPoseFixedBytes + kPoseSensorBytes * kMaxSensors;
/// Largest payload of any block type this version knows or skips.
inline constexpr std::size_t kMaxBlockPayload = kRawPrefixBytes + kMaxRawChunk;

/// header_copy (4): a copy of the file header (all its bytes, magic to CRC) in one or more
/// blocks right after it, so a damaged header is recovered from them. Readers that do not know
/// the type skip it (checksum-valid unknown blocks are skipped by every version-1 reader).
/// compressed (5): a run of whole ordinary blocks (each with its sync marker and CRC) compressed
/// together into one zstd frame, by the writer thread when recording.compression = "zstd".
/// clock (6): the wall clock beside the monotonic one, written by the writer thread.
enum class BlockType : uint8_t {
  raw = 1,
  sample = 2,
  pose = 3,
  header_copy = 4,
  compressed = 5,
  clock = 6
};
/// header_copy payload prefix: u32 total header bytes, u32 offset of this chunk.
inline constexpr std::size_t kHeaderCopyPrefixBytes = 8;
inline constexpr std::size_t kHeaderCopyChunk = kMaxBlockPayload - kHeaderCopyPrefixBytes;

/// compressed payload: u32 length of the blocks it holds once decompressed (<= kMaxGroupBytes),
/// then one zstd frame of them.
inline constexpr std::size_t kCompressedPrefixBytes = 4;
inline constexpr std::size_t kMaxGroupBytes = 256u * 1024;
/// clock payload: i64 t_host_ns (CLOCK_MONOTONIC), i64 t_unix_ns (CLOCK_REALTIME), sampled back
/// to back.
inline constexpr std::size_t kClockPayloadBytes = 16;

/// One sensor of the rig as recorded in the header.
struct SensorDescription {
  std::string name;           ///< rig name, at most 255 bytes
  std::string protocol;       ///< driver protocol name (e.g. "witmotion"), at most 255 bytes
  int segment = -1;           ///< Segment index it drives, -1 if none
  uint16_t device_index = 0;  ///< index used in raw blocks for this sensor's device
  bool operator==(const SensorDescription&) const = default;
};

struct SessionHeader {
  int64_t t_start_unix_ns = 0;   ///< wall-clock time the recording started (CLOCK_REALTIME)
  int64_t t_start_host_ns = 0;   ///< host monotonic time at the same instant
  std::string config_text;       ///< the daemon configuration in force (TOML text)
  std::string calibration_text;  ///< the calibration in force (text), may be empty
  std::vector<SensorDescription> sensors;
  bool operator==(const SessionHeader&) const = default;
};

/// The complete file prefix (magic, version, endian tag, header, CRC). Returns false with a
/// message if a field exceeds its limit.
bool encode_file_header(const SessionHeader& header, std::vector<uint8_t>& out, std::string* error);
/// Appends the header_copy blocks (with block headers and CRCs) for a complete file prefix as
/// encode_file_header() made it.
void encode_header_copy_blocks(std::span<const uint8_t> file_header, std::vector<uint8_t>& out);
/// Parses the header payload (the bytes between the length field and the CRC).
bool decode_header_payload(std::span<const uint8_t> payload, SessionHeader& header,
                           std::string* error);

/// Writes the 128-byte sample payload. Allocates nothing.
void encode_sample(const ImuSample& s, uint8_t* out) noexcept;
/// Reads a sample payload; false if a value is not finite.
bool decode_sample(std::span<const uint8_t> payload, ImuSample& s) noexcept;
/// Writes the pose payload into out (room for kMaxPosePayload); returns its size.
std::size_t encode_pose(const PoseFrame& f, uint8_t* out) noexcept;
/// Reads a pose payload; false if its size does not match its sensor count or a value is not
/// finite.
bool decode_pose(std::span<const uint8_t> payload, PoseFrame& f) noexcept;

/// Writes the raw-block prefix (device index, t_host_ns).
void encode_raw_prefix(uint16_t device_index, int64_t t_host_ns, uint8_t* out) noexcept;
/// Writes the 8-byte block header for a payload of the given size.
void encode_block_header(BlockType type, uint32_t payload_len, uint8_t* out) noexcept;

// Little-endian primitives (explicit byte order, independent of the host): one load or store,
// swapped on a big-endian host (byte-by-byte loops did not compile to single loads, and a
// replay decodes millions of fields).
inline uint16_t to_little_endian(uint16_t v) {
  if constexpr (std::endian::native == std::endian::big) return __builtin_bswap16(v);
  return v;
}
inline uint32_t to_little_endian(uint32_t v) {
  if constexpr (std::endian::native == std::endian::big) return __builtin_bswap32(v);
  return v;
}
inline uint64_t to_little_endian(uint64_t v) {
  if constexpr (std::endian::native == std::endian::big) return __builtin_bswap64(v);
  return v;
}
template <typename T>
inline void put_le(uint8_t* p, T v) {
  v = to_little_endian(v);
  std::memcpy(p, &v, sizeof v);
}
template <typename T>
inline T get_le(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return to_little_endian(v);
}
inline void put_u16(uint8_t* p, uint16_t v) {
  put_le(p, v);
}
inline void put_u32(uint8_t* p, uint32_t v) {
  put_le(p, v);
}
inline void put_u64(uint8_t* p, uint64_t v) {
  put_le(p, v);
}
inline uint16_t get_u16(const uint8_t* p) {
  return get_le<uint16_t>(p);
}
inline uint32_t get_u32(const uint8_t* p) {
  return get_le<uint32_t>(p);
}
inline uint64_t get_u64(const uint8_t* p) {
  return get_le<uint64_t>(p);
}

}  // namespace mocap::session
