// Looking a receiver and its kind's traits up among those registered (each from its own .cpp),
// and the scaling of a pulse's returns.
#include "pipeline/shot/receiver.hpp"

#include "core/error.hpp"

namespace glaswave {
namespace {

[[noreturn]] void unknown(const std::string& name, const std::vector<std::string>& known) {
  std::string list;
  for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
  throw setting_error(ErrorKind::config, "kind",
                      "no receiver \"" + name + "\" (there are: " + list + ")");
}

ReceiverKind kind_of(const std::string& name) {
  const Registry<Receiver>& receivers = Registry<Receiver>::instance();
  if (std::optional<ReceiverKind> kind = receivers.find(name)) return *std::move(kind);
  std::vector<std::string> known;
  for (const auto& entry : receivers.entries()) known.push_back(entry.name);
  unknown(name, known);
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

ReceiverTraits receiver_traits(const std::string& kind) {
  if (const std::optional<ReceiverTraits> traits = declared_traits<ReceiverTraits>(kind))
    return *traits;
  unknown(kind, declared_kinds<ReceiverTraits>());
}

}  // namespace glaswave
