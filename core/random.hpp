// The one counter-based random keying of glaswave, as pbrt's samplers key theirs: a stream is
// fixed by (seed, shot, ray) and the purpose that draws from it, and its successive draws are
// the dimensions. A shot's numbers are then the same bits for any thread count and any split of
// the track. The transport keys rays by (seed, shot, ray); the detector bins by (seed, shot,
// band and bin); the photon-counting receiver its events by (seed, shot, beam and bin); stands
// tiles by (seed, tile, kind of canopy); roughness lattice nodes by (seed, node, zone); the sun's
// photons of `brf` by (seed, batch, photon); the forward table's design by (seed, parameter).
#pragma once

#include <cstdint>
#include <pcg_random.hpp>

namespace glaswave {

// SplitMix64's finaliser: a bijective mix of 64 bits, so that neighbouring keys get unrelated
// streams.
constexpr std::uint64_t mix_bits(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Who draws: each purpose has streams of its own under the same seed. The transport's is 0, so
// its streams are keyed by the seed itself.
enum class RandomPurpose : std::uint64_t {
  transport = 0,
  detector = 0xd37ec70b5eed5a17ULL,
  stand = 0x57a9d7ee5c0ffee1ULL,
  roughness = 0x2009e1a7715ce5adULL,
  sun = 0x5a7b1e55f0c0ffeeULL,           // `brf`: photons traced from the sun
  sky = 0x5c71a7e5b0c0ffeeULL,           // the sky's light for the background, by (node, photon)
  beam_points = 0xb3a9501b01c0ffeeULL,   // the transport's scrambling of a shot's Sobol' points
  photons = 0x9407025c0a7e1a5eULL,       // photon counting: a shot's photon events by (beam, bin)
  table_design = 0x7ab1e5d0e5161c0dULL,  // `glaswave table`: the design's shift by (parameter)
  photon_calibration = 0xca1b9407025c0a7eULL,  // rt on photons: a table entry's draws by (entry)
};

// Two signed indices (a 2-D grid's row and column, each within +-2^31) as one key.
constexpr std::uint64_t pair_key(std::int64_t high, std::int64_t low) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(high)) << 32) |
         static_cast<std::uint32_t>(low);
}

class RandomStream {
 public:
  RandomStream(std::uint64_t seed, std::uint64_t shot, std::uint64_t ray,
               RandomPurpose purpose = RandomPurpose::transport)
      : engine_(keyed(seed ^ static_cast<std::uint64_t>(purpose), shot)) {
    engine_.advance(ray << ray_bits);
  }

  // Uniform in [0, 1): one dimension, two 32-bit draws.
  double uniform() {
    const std::uint64_t bits = (static_cast<std::uint64_t>(engine_()) << 21) ^ engine_();
    return static_cast<double>(bits & ((1ULL << 53) - 1)) * 0x1.0p-53;
  }

 private:
  friend class RandomStreams;
  friend class ShotStreams;
  static constexpr unsigned ray_bits = 32;  // 2^32 numbers a ray before streams could overlap

  // pcg32 with its state reachable, for RandomStreams' step.
  class Engine : public pcg32 {
   public:
    Engine(std::uint64_t state, std::uint64_t stream) : pcg32(state, stream) {}
    std::uint64_t state() const { return state_; }
    void set_state(std::uint64_t state) { state_ = state; }
    std::uint64_t stream_increment() const { return increment(); }
  };

  explicit RandomStream(const Engine& engine) : engine_(engine) {}
  // (seed ^ purpose, shot)'s engine, before its advance to the ray.
  static Engine keyed(std::uint64_t key, std::uint64_t shot) {
    return Engine(mix_bits(key ^ mix_bits(shot)),
                  mix_bits(shot + 0x9e3779b97f4a7c15ULL * (key + 1)));
  }

  Engine engine_;
};

// The streams of one (seed, shot, purpose) for rays asked in increasing order, each the same
// bits as RandomStream(seed, shot, ray, purpose). Keying a ray advances the engine by ray << 32
// draws (up to 59 squarings of the multiplier); consecutive rays' streams are 2^32 draws apart,
// one affine step A s + C of the last one's state (an LCG's advance composes), so a run of
// consecutive rays, or a short gap, costs a multiplication a ray. The photon draw asks its bins in
// order.
class RandomStreams {
 public:
  // A ray up to this many on from the last is stepped to (a multiplication a ray), one further
  // keyed afresh (up to 59 squarings).
  static constexpr std::uint64_t most_steps = 32;

  RandomStreams(std::uint64_t seed, std::uint64_t shot, RandomPurpose purpose)
      : base_(RandomStream::keyed(seed ^ static_cast<std::uint64_t>(purpose), shot)), last_(base_) {
    // The step's A and C from the engine's own advance: f(0) = C, f(1) = A + C.
    RandomStream::Engine probe = base_;
    probe.set_state(0);
    probe.advance(std::uint64_t{1} << RandomStream::ray_bits);
    step_plus_ = probe.state();
    probe.set_state(1);
    probe.advance(std::uint64_t{1} << RandomStream::ray_bits);
    step_mult_ = probe.state() - step_plus_;
  }

  RandomStream at(std::uint64_t ray) {
    if (have_last_ && ray > last_ray_ && ray - last_ray_ <= most_steps) {
      for (std::uint64_t step = last_ray_; step < ray; ++step)
        last_.set_state(step_mult_ * last_.state() + step_plus_);
    } else {
      last_ = base_;
      last_.advance(ray << RandomStream::ray_bits);
    }
    have_last_ = true;
    last_ray_ = ray;
    return RandomStream(last_);
  }

 private:
  RandomStream::Engine base_, last_;
  bool have_last_ = false;
  std::uint64_t last_ray_ = 0;
  std::uint64_t step_mult_ = 0, step_plus_ = 0;
};

// The streams of one (seed, ray, purpose) for many shots (the roughness's lattice nodes, keyed
// by node at the zone's ray), each the same bits as RandomStream(seed, shot, ray, purpose). The
// constructor's advance to the ray takes up to 59 squarings a stream; for a fixed ray it is
// one affine step of the shot's engine, A s + G inc (pcg's advance is linear in the state and
// in the stream's increment), A and G found once here.
class ShotStreams {
 public:
  ShotStreams(std::uint64_t seed, std::uint64_t ray, RandomPurpose purpose)
      : key_(seed ^ static_cast<std::uint64_t>(purpose)) {
    RandomStream::Engine probe(0, 0);  // stream 0: increment 1
    probe.set_state(0);
    probe.advance(ray << RandomStream::ray_bits);
    plus_per_increment_ = probe.state();
    probe.set_state(1);
    probe.advance(ray << RandomStream::ray_bits);
    mult_ = probe.state() - plus_per_increment_;
  }

  RandomStream at(std::uint64_t shot) const {
    RandomStream::Engine engine = RandomStream::keyed(key_, shot);
    engine.set_state(mult_ * engine.state() + plus_per_increment_ * engine.stream_increment());
    return RandomStream(engine);
  }

 private:
  std::uint64_t key_;
  std::uint64_t mult_ = 0, plus_per_increment_ = 0;
};

// The transport's name for its ray streams.
using RayRandom = RandomStream;

}  // namespace glaswave
