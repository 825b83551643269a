// BvhOutput: frames through the dropout bridge into the skeleton's BvhWriter.
#include "mocap/outputs/bvh_output.hpp"

namespace mocap::outputs {

BvhOutput::BvhOutput(const std::string& path, const BodyModelConfig& model, double frame_time_s)
    : bridge_(BodyModel(model).dimensions()) {
  BvhWriterOptions o;
  o.frame_time_s = frame_time_s;
  writer_ = std::make_unique<BvhWriter>(path, BodyModel(model), o);
}

void BvhOutput::on_frame(const PoseFrame& f) {
  bridge_.push(f);
  drain();
}

void BvhOutput::close() {
  bridge_.finish();
  drain();
  writer_->close();
}

void BvhOutput::drain() {
  while (bridge_.next(out_))
    writer_->write_frame(out_);
}

}  // namespace mocap::outputs
