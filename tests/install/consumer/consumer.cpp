// Built by the install test from a project that sets no language standard of its own: the
// package must carry C++20, or <glaswave/glaswave.hpp> does not compile ('std::span' has not
// been declared). It parses a configuration through the library, so the link is checked too.
#include <cstdio>
#include <glaswave/glaswave.hpp>

int main() try {
  const glaswave::Config config = glaswave::parse_config(
      {{"sensor", {{"preset", "glas"}}},
       {"terrain", {{"plane", {{"origin_lat_deg", 0.0}, {"origin_lon_deg", 0.0}}}}},
       {"canopy", nullptr},
       {"track", {{"type", "points"}, {"points", {{{"lat_deg", 0.0}, {"lon_deg", 0.0}}}}}}});
  std::printf("consumer: C++ %ld, a configuration of %zu bands\n", static_cast<long>(__cplusplus),
              config.sensor.bands.size());
  return __cplusplus >= 202002L ? 0 : 1;
} catch (const glaswave::Error& e) {
  std::fprintf(stderr, "consumer: error: %s\n", e.what());
  return e.exit_status();
}
