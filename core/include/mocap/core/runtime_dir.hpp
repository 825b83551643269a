// Where mocapd keeps its runtime files (control socket, instance lock): a directory only the
// user can use. $XDG_RUNTIME_DIR when set; otherwise /tmp/mocapd-<uid> created with mode 0700,
// and accepted only if lstat() shows a real directory (not a symlink) owned by the user with no
// group/other access; if another user took that name first, $HOME/.cache/mocapd (same checks).
// Never a predictable file another user can create first.
#pragma once

#include <string>

namespace mocap {

/// Creates `path` (mode 0700) if missing and checks it with lstat: a directory, not a symlink,
/// owned by the effective uid, no group/other permissions. False with the reason.
bool ensure_private_dir(const std::string& path, std::string* why);

/// The runtime directory (see above); "" with the reason when none is usable.
/// `tmp_base` (default "/tmp") and `home` (default $HOME) exist for tests.
std::string private_runtime_dir(std::string* error = nullptr, const char* tmp_base = nullptr,
                                const char* home = nullptr);

}  // namespace mocap
