// A fresh directory in the system's temp area for a test, removed with its content.
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace mocap::test {

class TempDir {
 public:
  /// `prefix` names the test area in the directory's name (mocap-PREFIX-XXXXXX).
  explicit TempDir(const std::string& prefix = "io") {
    std::string tmpl =
        (std::filesystem::temp_directory_path() / ("mocap-" + prefix + "-XXXXXX")).string();
    if (::mkdtemp(tmpl.data())) path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    if (!path_.empty()) std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  /// Empty when the directory could not be made.
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace mocap::test
