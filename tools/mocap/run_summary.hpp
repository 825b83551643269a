// The one-line report `mocap replay` and `mocap export` print on stdout when they finish: one
// JSON object with the same keys for both (command, input, outputs, frames, duration_s, then the
// command's own), numbers rounded to their precision. Warnings and errors go to stderr.
#pragma once

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace mocap::cmd {

inline void print_run_summary(const std::string& command, const std::string& input,
                              const std::vector<std::string>& outputs, long long frames,
                              double duration_s, const nlohmann::json& extra) {
  nlohmann::ordered_json j;
  j["command"] = command;
  j["input"] = input;
  j["outputs"] = outputs;
  j["frames"] = frames;
  j["duration_s"] = std::round(duration_s * 1000) / 1000;
  for (auto it = extra.begin(); it != extra.end(); ++it)
    j[it.key()] = it.value();
  std::printf("%s\n", j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
  std::fflush(stdout);
}

}  // namespace mocap::cmd
