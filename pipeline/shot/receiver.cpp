// Looking a receiver up by its kind among those registered (each from its own .cpp), and the
// scaling of a pulse's returns.
#include "pipeline/shot/receiver.hpp"

#include "core/error.hpp"

namespace glaswave {
namespace {

ReceiverKind kind_of(const std::string& name) {
  const Registry<Receiver>& receivers = Registry<Receiver>::instance();
  if (std::optional<ReceiverKind> kind = receivers.find(name)) return *std::move(kind);
  std::string known;
  for (const auto& entry : receivers.entries()) known += (known.empty() ? "" : ", ") + entry.name;
  throw setting_error(ErrorKind::config, "kind",
                      "no receiver \"" + name + "\" (there are: " + known + ")");
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

std::unique_ptr<Receiver> make_receiver(const ReceiverSettings& settings) {
  return kind_of(settings.kind).make(settings);
}

ReceiverTraits receiver_traits(const std::string& kind) { return kind_of(kind).traits; }

}  // namespace glaswave
