// Exclusive creation of recording files inside recording.directory (recording_file.hpp).
#include "mocap/outputs/recording_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace mocap::outputs {

namespace fs = std::filesystem;

namespace {

std::string errno_text(int e) {
  if (e == ELOOP) return "is a symbolic link (refused)";
  return std::strerror(e);
}

/// `name` split into components relative to `directory`, or an error message.
std::vector<std::string> relative_components(const std::string& directory, const std::string& name,
                                             std::string& error) {
  fs::path p(name);
  for (const auto& c : p)
    if (c == "..") {
      error = "'" + name + "': '..' is not allowed in recording names";
      return {};
    }
  if (p.is_absolute()) {
    // Inside the directory, as written or after resolving the directory's own symlinks.
    std::error_code ec;
    const fs::path norm = p.lexically_normal();
    const fs::path dir_abs = fs::absolute(directory, ec).lexically_normal();
    const fs::path dir_real = fs::weakly_canonical(dir_abs, ec);
    fs::path rel;
    for (const fs::path& d : {dir_abs, dir_real}) {
      const fs::path r = norm.lexically_relative(d);
      if (!r.empty() && r != "." && *r.begin() != "..") {
        rel = r;
        break;
      }
    }
    if (rel.empty()) {
      error = "'" + name + "' is outside recording.directory (" + dir_abs.string() +
              "): give a name inside it";
      return {};
    }
    p = rel;
  }
  std::vector<std::string> out;
  for (const auto& c : p) {
    const std::string s = c.string();
    if (s.empty() || s == "." || s == "/") continue;
    out.push_back(s);
  }
  if (out.empty()) error = "'" + name + "' does not name a file";
  return out;
}

std::string with_suffix(const std::string& leaf, int n) {
  if (n <= 1) return leaf;
  const auto dot = leaf.find_last_of('.');
  const std::string stem = dot == std::string::npos || dot == 0 ? leaf : leaf.substr(0, dot);
  const std::string ext = dot == std::string::npos || dot == 0 ? "" : leaf.substr(dot);
  return stem + "-" + std::to_string(n) + ext;
}

}  // namespace

std::string default_take_name(std::time_t now) {
  std::tm tm{};
  localtime_r(&now, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "take-%Y%m%d-%H%M%S", &tm);
  return std::string(buf) + "." + kSessionExtension;
}

RecordingFile create_recording_file(const std::string& directory, const std::string& name,
                                    bool unique, std::time_t now) {
  const std::string dir = directory.empty() ? std::string(".") : directory;
  std::string error;
  std::vector<std::string> parts;
  if (name.empty()) {
    parts.push_back(default_take_name(now));
    unique = true;
  } else {
    parts = relative_components(dir, name, error);
    if (parts.empty()) throw std::runtime_error("cannot record to " + error);
  }
  // Walk the directories without following symlinks.
  int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0)
    throw std::runtime_error("cannot open recording.directory '" + dir +
                             "': " + std::strerror(errno));
  std::string path = dir;
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    path += "/" + parts[i];
    const int next =
        ::openat(dfd, parts[i].c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    const int e = errno;
    ::close(dfd);
    if (next < 0) {
      // A symlink fails with ELOOP or ENOTDIR (O_DIRECTORY is checked on the link itself).
      throw std::runtime_error(
          "cannot create session file '" + (name.front() == '/' ? name : dir + "/" + name) +
          "': directory '" + path + "' " +
          (e == ENOENT                    ? std::string("does not exist")
           : (e == ENOTDIR || e == ELOOP) ? std::string("is not a directory (symlinks are refused)")
                                          : errno_text(e)));
    }
    dfd = next;
  }
  const std::string leaf = parts.back();
  const std::string dir_path = path;
  for (int n = 1; n < 10000; ++n) {
    const std::string candidate = with_suffix(leaf, n);
    const int fd = ::openat(dfd, candidate.c_str(),
                            O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd >= 0) return RecordingFile{fd, dfd, candidate, dir_path + "/" + candidate};
    const int e = errno;
    if (e == EEXIST && unique) continue;
    ::close(dfd);
    if (e == EEXIST)
      throw std::runtime_error("session file '" + dir_path + "/" + candidate +
                               "' already exists: recordings are never overwritten (give a new "
                               "name, or none for a fresh take-DATE-TIME name)");
    throw std::runtime_error("cannot create session file '" + dir_path + "/" + candidate +
                             "': " + errno_text(e));
  }
  ::close(dfd);
  throw std::runtime_error("no free name for '" + dir_path + "/" + leaf + "'");
}

}  // namespace mocap::outputs
