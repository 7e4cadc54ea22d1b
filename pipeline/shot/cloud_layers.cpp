// The reported layers as the granules' flags take them (cloud_layers.hpp).
#include "pipeline/shot/cloud_layers.hpp"

#include "pipeline/transport/atmosphere.hpp"

namespace glaswave {

std::vector<CloudLayer> reported_cloud_layers(const AtmosphereSettings& atmosphere,
                                              std::size_t band) {
  std::vector<CloudLayer> layers;
  for (const std::size_t i : detected_layers(atmosphere, band)) {
    const AtmosphereLayer& layer = atmosphere.layers[i];
    layers.push_back({layer.base_m, layer.above_ellipsoid});
  }
  return layers;
}

}  // namespace glaswave
