// Parsing of "VID:PID[:SERIAL]" device addresses shared by the serial, HID and USB transports.
#include <charconv>

#include "mocap/drivers/transport.hpp"

namespace mocap {

bool parse_usb_ids(const std::string& text, UsbIds& ids, std::string& err) {
  const auto c1 = text.find(':');
  if (c1 == std::string::npos) {
    err = "\"" + text + "\": expected VID:PID[:SERIAL] with hexadecimal ids, e.g. 054c:09cc";
    return false;
  }
  auto c2 = text.find(':', c1 + 1);
  const std::string vid = text.substr(0, c1);
  const std::string pid =
      text.substr(c1 + 1, c2 == std::string::npos ? std::string::npos : c2 - c1 - 1);
  auto hex = [](const std::string& s, uint16_t& out) {
    std::string_view v(s);
    if (v.substr(0, 2) == "0x" || v.substr(0, 2) == "0X") v.remove_prefix(2);
    unsigned x = 0;
    const auto r = std::from_chars(v.data(), v.data() + v.size(), x, 16);
    if (v.empty() || r.ec != std::errc() || r.ptr != v.data() + v.size() || x > 0xFFFF)
      return false;
    out = static_cast<uint16_t>(x);
    return true;
  };
  if (!hex(vid, ids.vid) || !hex(pid, ids.pid)) {
    err = "\"" + text + "\": VID and PID must be hexadecimal numbers up to ffff";
    return false;
  }
  ids.serial = c2 == std::string::npos ? "" : text.substr(c2 + 1);
  return true;
}

}  // namespace mocap
