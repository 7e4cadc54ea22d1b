// The registry of receivers, with the analog waveform receiver registered from the start.
#include "pipeline/shot/receiver.hpp"

#include <map>
#include <mutex>

#include "core/error.hpp"
#include "pipeline/shot/photon_receiver.hpp"
#include "pipeline/shot/waveform_receiver.hpp"

namespace glaswave {
namespace {

struct Registry {
  std::mutex mutex;
  std::map<std::string, ReceiverFactory> kinds;
};

Registry& registry() {
  static Registry receivers{
      {},
      {{"waveform",
        [](const ReceiverSettings& s) { return std::make_unique<WaveformReceiver>(s); }},
       {"photon_counting",
        [](const ReceiverSettings& s) { return std::make_unique<PhotonCountingReceiver>(s); }}}};
  return receivers;
}

}  // namespace

void scale_pulse_energy(ShotWaveforms& w, double scale) {
  if (scale == 1.0) return;
  auto times = [](std::vector<double>& v, double k) {
    for (double& x : v) x *= k;
  };
  for (auto* set : {&w.total_W, &w.canopy_W, &w.ground_W})
    for (auto& band : *set) times(band, scale);
  for (auto& band : w.total_variance_W2) times(band, scale * scale);
  for (auto& band : w.order_W)
    for (auto& order : band) times(order, scale);
  for (auto* set : {&w.scored.total_J, &w.scored.canopy_J, &w.scored.ground_J})
    for (auto& band : *set) times(band, scale);
  for (auto& band : w.scored.order_J)
    for (auto& order : band) times(order, scale);
  times(w.energy_J, scale);
  times(w.canopy_energy_J, scale);
  times(w.ground_energy_J, scale);
}

void register_receiver(const std::string& name, ReceiverFactory make) {
  Registry& receivers = registry();
  const std::lock_guard lock(receivers.mutex);
  if (!receivers.kinds.emplace(name, std::move(make)).second)
    throw run_error("receiver \"" + name + "\"", "registered twice");
}

std::unique_ptr<Receiver> make_receiver(const ReceiverSettings& settings) {
  Registry& receivers = registry();
  ReceiverFactory make;
  {
    const std::lock_guard lock(receivers.mutex);
    const auto found = receivers.kinds.find(settings.kind);
    if (found == receivers.kinds.end()) {
      std::string known;
      for (const auto& [name, factory] : receivers.kinds)
        known += (known.empty() ? "" : ", ") + name;
      throw setting_error(ErrorKind::config, "kind",
                          "no receiver \"" + settings.kind + "\" (there are: " + known + ")");
    }
    make = found->second;
  }
  return make(settings);
}

}  // namespace glaswave
