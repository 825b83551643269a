// The devices `mocap setup` listens to (see listener.hpp).
#include "mocap/setup/listener.hpp"

#include <chrono>
#include <thread>

#include "mocap/daemon/daemon.hpp"

namespace mocap::setup {

Listener::Listener(std::vector<Candidate> candidates, Logger log)
    : candidates_(std::move(candidates)), log_(std::move(log)), meter_(candidates_.size()) {
  for (std::size_t i = 0; i < candidates_.size(); ++i) {
    daemon::SensorConfig s = candidates_[i].sensor;
    s.name = candidates_[i].what;  // only for the drivers' log lines
    cfg_.sensors.push_back(std::move(s));
  }
}

Listener::~Listener() {
  stop();
}

void Listener::stop() {
  for (auto& [i, d] : devices_)
    d->stop();
  devices_.clear();
}

void Listener::open(std::size_t leader) {
  auto it = devices_.find(leader);
  if (it != devices_.end()) {
    it->second->stop();
    devices_.erase(it);
  }
  try {
    const DeviceSpec spec = daemon::device_spec(cfg_, leader);
    auto dev = make_device(spec, log_.child("device", log_.level()));
    dev->start(meter_);
    devices_[leader] = std::move(dev);
  } catch (const std::exception& e) {
    log_.warn("%s: %s", candidates_[leader].what.c_str(), e.what());
  }
}

void Listener::probe(double probe_s, const std::function<void(const std::string&)>& progress) {
  for (std::size_t i = 0; i < candidates_.size(); ++i)
    if (daemon::device_leader(cfg_, i) == i) open(i);
  const auto wait = [&] {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(probe_s);
    while (std::chrono::steady_clock::now() < end) {
      bool all = true;
      for (std::size_t i = 0; i < candidates_.size() && all; ++i)
        all = heard(i) || candidates_[i].optional;
      if (all) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  };
  for (;;) {
    wait();
    bool reopened = false;
    for (std::size_t i = 0; i < candidates_.size(); ++i) {
      Candidate& c = candidates_[i];
      if (heard(i) || c.probe + 1 >= c.probes.size() || daemon::device_leader(cfg_, i) != i)
        continue;
      ++c.probe;
      apply_probe(c);
      cfg_.sensors[i].driver = c.sensor.driver;
      cfg_.sensors[i].baud = c.sensor.baud;
      cfg_.sensors[i].rate_hz = c.sensor.rate_hz;
      if (progress)
        progress(c.what + ": nothing as " + c.probes[c.probe - 1].driver + "; trying " +
                 c.sensor.driver +
                 (c.sensor.baud > 0 ? " at " + std::to_string(c.sensor.baud) + " baud" : ""));
      open(i);
      reopened = true;
    }
    if (!reopened) break;
  }
  // A device that gave nothing with any setting is closed (no retrying in the background).
  for (auto it = devices_.begin(); it != devices_.end();) {
    bool any = false;
    for (std::size_t i = 0; i < candidates_.size(); ++i)
      any = any || (daemon::device_leader(cfg_, i) == it->first && heard(i));
    if (any) {
      ++it;
    } else {
      it->second->stop();
      it = devices_.erase(it);
    }
  }
}

}  // namespace mocap::setup
