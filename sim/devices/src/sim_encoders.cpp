// make_encoder(): the simulated-device encoder for each protocol name.
#include <stdexcept>
#include <string>

#include "sim_common.hpp"

namespace mocap {

std::unique_ptr<ProtocolEncoder> make_encoder(std::string_view protocol,
                                              const EncoderOptions& opt) {
  if (!(opt.rate_hz > 0 && opt.rate_hz <= 10000))
    throw std::invalid_argument("simulated device: rate must be in (0, 10000] Hz");
  if (protocol == "line") return make_line_encoder(opt);
  if (protocol == "witmotion") return make_witmotion_encoder(opt);
  if (protocol == "xbus") return make_xbus_encoder(opt);
  if (protocol == "ds4") return make_playstation_encoder(opt, false);
  if (protocol == "dualsense") return make_playstation_encoder(opt, true);
  if (protocol == "joycon") return make_joycon_encoder(opt);
  if (protocol == "slimevr_hid") return make_slimevr_hid_encoder(opt);
  throw std::invalid_argument("simulated device: unknown protocol \"" + std::string(protocol) +
                              "\" (known: witmotion, xbus, ds4, dualsense, joycon, line, "
                              "slimevr_hid; slimevr boards: SimSlimeTracker)");
}

}  // namespace mocap
