// CSV writers for simulated IMU streams and ground truth (see csv_writers.hpp).
#include "mocap/sim/csv_writers.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace mocap::sim {

CsvFile::CsvFile(const std::string& path, std::string_view header) : path_(path) {
  f_ = std::fopen(path.c_str(), "w");
  if (!f_)
    throw std::runtime_error("cannot open '" + path + "' for writing: " + std::strerror(errno));
  std::fprintf(f_, "%.*s\n", static_cast<int>(header.size()), header.data());
}

CsvFile::~CsvFile() {
  if (f_) std::fclose(f_);
}

void CsvFile::close() {
  if (!f_) return;
  const bool failed = std::ferror(f_) != 0;
  const bool close_failed = std::fclose(f_) != 0;
  f_ = nullptr;
  if (failed || close_failed) throw std::runtime_error("error writing '" + path_ + "'");
}

ImuCsvWriter::ImuCsvWriter(const std::string& path, std::vector<std::string> sensor_names,
                           int64_t t0_ns)
    : CsvFile(path, kHeader), names_(std::move(sensor_names)), t0_ns_(t0_ns) {}

void ImuCsvWriter::write(const ImuSample& s) {
  const std::string unknown = "sensor" + std::to_string(s.sensor_id);
  const std::string& n = s.sensor_id < names_.size() ? names_[s.sensor_id] : unknown;
  const auto& g = s.gyr_rad_s;
  const auto& a = s.acc_m_s2;
  const auto& m = s.mag_uT;
  std::fprintf(f_, "%.9f,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n",
               static_cast<double>(s.t_host_ns - t0_ns_) * 1e-9, n.c_str(), g.x(), g.y(), g.z(),
               a.x(), a.y(), a.z(), m.x(), m.y(), m.z());
}

TruthCsvWriter::TruthCsvWriter(const std::string& path) : CsvFile(path, kHeader) {}

void TruthCsvWriter::write(const TruthFrame& f) {
  for (int i = 0; i < kSegmentCount; ++i) {
    const auto& q = f.q_earth_segment[i];
    const auto& p = f.p_earth_segment_m[i];
    std::fprintf(f_, "%.9f,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", f.t_s,
                 std::string(kSegmentNames[i]).c_str(), q.w(), q.x(), q.y(), q.z(), p.x(), p.y(),
                 p.z());
  }
}

}  // namespace mocap::sim
