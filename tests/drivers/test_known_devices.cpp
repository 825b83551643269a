// The udev rules must let a normal user open every device the drivers know (HID and Xsens ids
// by vendor and product, serial chips by vendor).
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include "mocap/drivers/known_devices.hpp"

TEST(KnownDevices, UdevRulesCoverEveryKnownId) {
  std::ifstream in(MOCAP_SOURCE_DIR "/config/udev/70-mocap.rules");
  ASSERT_TRUE(in) << "config/udev/70-mocap.rules missing";
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string rules = ss.str();
  for (const auto& k : mocap::known_devices()) {
    char vid[64], both[128];
    std::snprintf(vid, sizeof vid, "idVendor}==\"%04x\"", k.vid);
    std::snprintf(both, sizeof both, "idVendor}==\"%04x\", ATTRS{idProduct}==\"%04x\"", k.vid,
                  k.pid);
    const bool by_vendor_only = rules.find(std::string(vid) + ", MODE") != std::string::npos;
    EXPECT_TRUE(rules.find(both) != std::string::npos || by_vendor_only)
        << "no udev rule for " << k.what << " " << both;
  }
}
