// Private runtime directory (runtime_dir.hpp).
#include "mocap/core/runtime_dir.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace mocap {

bool ensure_private_dir(const std::string& path, std::string* why) {
  auto fail = [&](const std::string& m) {
    if (why) *why = path + ": " + m;
    return false;
  };
  if (::mkdir(path.c_str(), 0700) != 0 && errno != EEXIST)
    return fail(std::string("cannot create: ") + std::strerror(errno));
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return fail(std::strerror(errno));
  if (S_ISLNK(st.st_mode)) return fail("is a symbolic link (refused)");
  if (!S_ISDIR(st.st_mode)) return fail("is not a directory");
  if (st.st_uid != ::geteuid())
    return fail("is owned by uid " + std::to_string(st.st_uid) + ", not by us (uid " +
                std::to_string(::geteuid()) + ")");
  if (st.st_mode & 077) return fail("is accessible to other users (mode must be 0700)");
  return true;
}

std::string private_runtime_dir(std::string* error, const char* tmp_base, const char* home) {
  if (const char* dir = std::getenv("XDG_RUNTIME_DIR"); dir && *dir) return dir;
  std::string why_tmp, why_home;
  const std::string tmp =
      std::string(tmp_base ? tmp_base : "/tmp") + "/mocapd-" + std::to_string(::geteuid());
  if (ensure_private_dir(tmp, &why_tmp)) return tmp;
  if (!home) home = std::getenv("HOME");
  if (home && *home) {
    const std::string cache = std::string(home) + "/.cache";
    ::mkdir(cache.c_str(), 0700);  // usually there already
    const std::string dir = cache + "/mocapd";
    if (ensure_private_dir(dir, &why_home)) return dir;
  } else {
    why_home = "$HOME is not set";
  }
  if (error)
    *error = "no private runtime directory (set XDG_RUNTIME_DIR): " + why_tmp + "; " + why_home;
  return {};
}

}  // namespace mocap
