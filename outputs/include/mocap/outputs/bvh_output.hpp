// BVH file output (`mocap replay --bvh`): the frames as BVH motion, a sensor's short dropouts
// bridged (as `mocap export` does). Writes as it goes, so it is for offline runs (replay wraps it
// in a FrameWriterThread), never for the live pipeline.
#pragma once

#include <memory>
#include <string>

#include "mocap/outputs/output.hpp"
#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/dropout_bridge.hpp"

namespace mocap::outputs {

class BvhOutput final : public Output {
 public:
  /// Creates the file for `model` (throws std::runtime_error naming it on failure).
  BvhOutput(const std::string& path, const BodyModelConfig& model, double frame_time_s);
  void on_frame(const PoseFrame& f) override;
  /// Writes the frames still held by the dropout bridge and closes the file (throws on failure).
  void close();
  int frames() const { return writer_->frames(); }

 private:
  void drain();
  DropoutBridge bridge_;
  PoseFrame out_;
  std::unique_ptr<BvhWriter> writer_;
};

}  // namespace mocap::outputs
