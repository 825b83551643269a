// filter_param_table: every [filter] key / --set name binds a member of its own in the per-stage
// FilterParams structs, and set_filter_param parses and reports by those names.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "mocap/filter/filter_param_names.hpp"

namespace mocap {
namespace {

TEST(FilterParamNames, EveryKeyBindsAMemberOfItsOwn) {
  FilterParams p;
  const auto table = filter_param_table();
  ASSERT_EQ(table.size(), 25u);  // as VQF's; the rest are fixed constants
  std::set<std::string> names, members;
  // Distinct values through the table; a key that aliased another's member would read back the
  // later one's value.
  for (size_t i = 0; i < table.size(); ++i) {
    const FilterParamEntry& e = table[i];
    EXPECT_TRUE(names.insert(e.name).second) << e.name;
    EXPECT_TRUE(members.insert(e.member).second) << e.member;
    EXPECT_NE(std::string(e.member).find('.'), std::string::npos) << e.member;  // stage.field
    if (e.is_flag())
      e.flag(p) = i % 2 == 0;
    else
      e.number(p) = 1000.0 + static_cast<double>(i);
  }
  for (size_t i = 0; i < table.size(); ++i) {
    const FilterParamEntry& e = table[i];
    const FilterParams& cp = p;
    if (e.is_flag())
      EXPECT_EQ(e.flag(cp), i % 2 == 0) << e.name;
    else
      EXPECT_EQ(e.number(cp), 1000.0 + static_cast<double>(i)) << e.name;
  }
}

TEST(FilterParamNames, KeysSetTheStageMembers) {
  FilterParams p;
  std::string err;
  ASSERT_TRUE(set_filter_param(p, "tau_acc_s=2.5", err)) << err;
  ASSERT_TRUE(set_filter_param(p, "bias_clip_deg_s=1.25", err)) << err;
  ASSERT_TRUE(set_filter_param(p, "mag_dist_rejection=false", err)) << err;
  ASSERT_TRUE(set_filter_param(p, "mag_trust_weight=0", err)) << err;
  ASSERT_TRUE(set_filter_param(p, "hard_iron_gate=0.04", err)) << err;
  ASSERT_TRUE(set_filter_param(p, "mag_latency_tau_s=15", err)) << err;
  ASSERT_TRUE(set_filter_param(p, "upset_gyr_deg_s=950", err)) << err;
  EXPECT_EQ(p.inclination.tau_acc_s, 2.5);
  EXPECT_EQ(p.bias.clip_deg_s, 1.25);
  EXPECT_FALSE(p.mag_dist.rejection);
  EXPECT_EQ(p.mag_dist.trust_weight, 0.0);
  EXPECT_EQ(p.hard_iron.gate, 0.04);
  EXPECT_EQ(p.mag_latency.tau_s, 15.0);
  EXPECT_EQ(p.upset.gyr_deg_s, 950.0);
  const std::string d = describe_filter_params(p);
  EXPECT_NE(d.find("bias_clip_deg_s=1.25\n"), std::string::npos) << d;
  EXPECT_NE(d.find("mag_dist_rejection=false\n"), std::string::npos) << d;
}

TEST(FilterParamNames, BadAssignmentsSayWhatIsWrong) {
  FilterParams p;
  std::string err;
  EXPECT_FALSE(set_filter_param(p, "tau_mag", err));
  EXPECT_NE(err.find("name=value"), std::string::npos) << err;
  EXPECT_FALSE(set_filter_param(p, "clip_deg_s=1", err));  // a member's name is not a key
  EXPECT_NE(err.find("unknown filter parameter 'clip_deg_s'"), std::string::npos) << err;
  EXPECT_FALSE(set_filter_param(p, "hard_iron_noise=0.05", err));  // a fixed constant now
  EXPECT_NE(err.find("filter_constants.hpp"), std::string::npos) << err;
  EXPECT_FALSE(set_filter_param(p, "tau_mag_s=12x", err));
  EXPECT_NE(err.find("not a number"), std::string::npos) << err;
  EXPECT_FALSE(set_filter_param(p, "rest_bias_est=maybe", err));
  EXPECT_NE(err.find("rest_bias_est"), std::string::npos) << err;
  EXPECT_EQ(p.heading.tau_mag_s, FilterParams{}.heading.tau_mag_s);  // untouched
}

}  // namespace
}  // namespace mocap
