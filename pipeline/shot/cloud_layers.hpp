// The cloud and aerosol layers a mission's layer finder would report in the simulated atmosphere,
// as the granules' flags take them (ATL08's msw_flag, cloud_flag_atm, layer_flag; GLAH14's
// elv_cloud_flg). Here, in the shot layer, because the engine reaches the transport through it.
#pragma once

#include <cstddef>
#include <vector>

#include "footprints/atmosphere_settings.hpp"
#include "pipeline/products/icesat2_products.hpp"

namespace glaswave {

// The layers transport's detected_layers reports at `band`, each as its base and what the base
// is measured from, in the atmosphere's order.
std::vector<CloudLayer> reported_cloud_layers(const AtmosphereSettings& atmosphere,
                                              std::size_t band);

}  // namespace glaswave
