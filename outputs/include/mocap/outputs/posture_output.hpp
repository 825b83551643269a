// The shared posture output ([outputs.posture]): each frame into the seqlocked shared memory the
// viewer reads (the layout, writer and reader: posture_shm.hpp). The object is held
// under an exclusive flock for the output's life, so a second mocapd publishing under the same name
// is refused before it creates (or, on exit, removes) anything. Wait-free for the pipeline.
#pragma once

#include <memory>

#include "mocap/outputs/output.hpp"
#include "mocap/outputs/registry.hpp"

namespace mocap::outputs {

/// The [outputs.posture] output (registry factory). Throws std::runtime_error when the object
/// is another user's, not private, or in use by another mocapd (it is then left untouched).
std::unique_ptr<Output> make_posture(const OutputsConfig& cfg, const OutputContext& ctx);

}  // namespace mocap::outputs
