// The output table: one row per output (name, the section that enables it, its factory), and
// make_outputs() building the enabled ones in the table's order.
#include "mocap/outputs/registry.hpp"

#include <stdexcept>
#include <string>

#include "mocap/outputs/json_stream.hpp"
#include "mocap/outputs/posture_output.hpp"
#include "mocap/outputs/vmc.hpp"
#include "mocap/outputs/vrchat.hpp"

namespace mocap::outputs {

namespace {
const OutputRow kOutputs[] = {
    {"posture", "outputs.posture", [](const OutputsConfig& c) { return c.posture.enabled; },
     make_posture},
    {"json", "outputs.json", [](const OutputsConfig& c) { return c.json.enabled; },
     make_json_stream},
    {"vmc", "outputs.vmc", [](const OutputsConfig& c) { return c.vmc.enabled; }, make_vmc},
    {"vrchat", "outputs.vrchat", [](const OutputsConfig& c) { return c.vrchat.enabled; },
     make_vrchat},
};
}  // namespace

std::span<const OutputRow> output_rows() {
  return kOutputs;
}

std::vector<std::unique_ptr<Output>> make_outputs(const OutputsConfig& cfg,
                                                  const OutputContext& ctx) {
  std::vector<std::unique_ptr<Output>> out;
  for (const OutputRow& row : kOutputs) {
    if (!row.enabled(cfg)) continue;
    try {
      out.push_back(row.make(cfg, ctx));
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string(row.section) + ": " + e.what());
    }
  }
  return out;
}

}  // namespace mocap::outputs
