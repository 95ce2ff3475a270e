// A small spring chain pushed by a moving tool, run by the scheduler with 1, 2 and 4 threads: the
// state hash after N frames must be bit-identical. It exercises the rules the schedule relies on:
// conflicting systems ordered by their declared access, per-element writes in parallel_for, float
// reductions through parallel_reduce_ordered, randomness keyed by (frame, element) only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/core/rng.hpp"
#include "engine/core/state_hash.hpp"
#include "engine/schedule/executor.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco {
namespace {

constexpr uint32_t kParticles = 6000;
constexpr uint32_t kGrain = 128;

struct Chain {
  std::vector<float> x, v, f;     // mm, mm/s, mN (1-D for brevity)
  std::vector<uint8_t> touching;  // particle within the tool's reach this frame
  float tool_x = 0;               // mm
  uint32_t contacts = 0;
  float kinetic = 0;              // sum 0.5 m v^2 with m = 1
  double centroid = 0;            // mm
  std::vector<float> energy_log;  // per frame
};

uint64_t hash_state(const Chain& c) {
  StateHash h;
  h.add(std::span<const float>(c.x));
  h.add(std::span<const float>(c.v));
  h.add(std::span<const float>(c.energy_log));
  h.add_value(c.contacts);
  h.add_value(c.centroid);
  return h.value();
}

std::vector<SystemDesc> chain_systems(Chain& c) {
  auto sys = [](std::string name, Phase phase, std::vector<std::string> r,
                std::vector<std::string> w, std::function<void(const FrameContext&)> run) {
    SystemDesc s{std::move(name), phase, std::move(r), std::move(w), {}, false, std::move(run)};
    return s;
  };
  return {
      sys("tool_track", Phase::Input, {}, {"tool.pose"},
          [&c](const FrameContext& ctx) {
            c.tool_x = 20.0f * std::sin(static_cast<float>(ctx.time_s) * 3.0f) + 30.0f;
          }),
      sys("contacts", Phase::Contacts, {"tool.pose", "chain.x"}, {"chain.touching", "contacts"},
          [&c](const FrameContext&) {
            parallel_for(0, kParticles, kGrain, [&c](uint32_t b, uint32_t e, int) {
              for (uint32_t i = b; i < e; ++i) c.touching[i] = std::fabs(c.x[i] - c.tool_x) < 0.5f;
            });
            c.contacts = parallel_reduce_ordered(
                0u, kParticles, kGrain, 0u,
                [&c](uint32_t b, uint32_t e) {
                  uint32_t n = 0;
                  for (uint32_t i = b; i < e; ++i) n += c.touching[i];
                  return n;
                },
                [](uint32_t a, uint32_t b) { return a + b; });
          }),
      sys("springs", Phase::Dynamics, {"chain.x", "chain.touching", "tool.pose"}, {"chain.f"},
          [&c](const FrameContext& ctx) {
            const CounterRng jitter(7);
            parallel_for(0, kParticles, kGrain, [&](uint32_t b, uint32_t e, int) {
              for (uint32_t i = b; i < e; ++i) {
                const float rest = 0.01f;
                float fi = 0;
                if (i > 0) fi -= 50.0f * (c.x[i] - c.x[i - 1] - rest);
                if (i + 1 < kParticles) fi += 50.0f * (c.x[i + 1] - c.x[i] - rest);
                if (c.touching[i]) fi += 5.0f * (c.x[i] - c.tool_x);
                fi += 1e-3f * (jitter.uniform(ctx.frame, i) - 0.5f);  // thermal jitter
                c.f[i] = fi;
              }
            });
          }),
      sys("integrate", Phase::Dynamics, {"chain.f"}, {"chain.x", "chain.v"},
          [&c](const FrameContext& ctx) {
            const float dt = static_cast<float>(ctx.dt_s);
            parallel_for(0, kParticles, kGrain, [&](uint32_t b, uint32_t e, int) {
              for (uint32_t i = b; i < e; ++i) {
                c.v[i] = 0.995f * c.v[i] + dt * c.f[i];  // semi-implicit Euler, light damping
                c.x[i] += dt * c.v[i];
              }
            });
          }),
      sys("kinetic_energy", Phase::Metrics, {"chain.v"}, {"metrics.energy"},
          [&c](const FrameContext&) {
            c.kinetic = parallel_reduce_ordered(
                0u, kParticles, kGrain, 0.0f,
                [&c](uint32_t b, uint32_t e) {
                  float s = 0;
                  for (uint32_t i = b; i < e; ++i) s += 0.5f * c.v[i] * c.v[i];
                  return s;
                },
                [](float a, float b) { return a + b; });
            c.energy_log.push_back(c.kinetic);
          }),
      sys("centroid", Phase::Metrics, {"chain.x"}, {"metrics.centroid"},
          [&c](const FrameContext&) {
            c.centroid = parallel_reduce_ordered(
                             0u, kParticles, kGrain, 0.0,
                             [&c](uint32_t b, uint32_t e) {
                               double s = 0;
                               for (uint32_t i = b; i < e; ++i) s += c.x[i];
                               return s;
                             },
                             [](double a, double b) { return a + b; }) /
                         kParticles;
          }),
  };
}

uint64_t run_chain(int threads, uint64_t frames, Chain& c, Dispatch dispatch = Dispatch::Auto) {
  c.x.resize(kParticles);
  for (uint32_t i = 0; i < kParticles; ++i) c.x[i] = 0.01f * static_cast<float>(i);
  c.v.assign(kParticles, 0.0f);
  c.f.assign(kParticles, 0.0f);
  c.touching.assign(kParticles, 0);
  const FrameGraph graph(chain_systems(c));
  // Access checking also trips on any race between systems.
  Executor ex(graph, threads, {.access_check = AccessCheck::On, .dispatch = dispatch});
  constexpr double kDt = 1.0 / 120.0;
  for (uint64_t f = 0; f < frames; ++f) ex.run_frame({f, static_cast<double>(f) * kDt, kDt});
  return hash_state(c);
}

TEST(Determinism, StateHashIsIdenticalFor1And2And4Threads) {
  constexpr uint64_t kFrames = 120;
  Chain one, two, four;
  const uint64_t h1 = run_chain(1, kFrames, one);
  const uint64_t h2 = run_chain(2, kFrames, two);
  const uint64_t h4 = run_chain(4, kFrames, four);
  EXPECT_EQ(h1, h2);
  EXPECT_EQ(h1, h4);
  // Whichever way the executor dispatches a frame (executor.hpp, Dispatch), the state is the same.
  for (const Dispatch d : {Dispatch::Graph, Dispatch::Serial}) {
    Chain again;
    EXPECT_EQ(run_chain(2, kFrames, again, d), h1) << int(d);
  }
  // The run did something worth hashing: the tool touched the chain and set it moving.
  EXPECT_EQ(one.energy_log.size(), kFrames);
  EXPECT_GT(one.kinetic, 0.0f);
  EXPECT_TRUE(std::isfinite(one.kinetic));
  const bool touched =
      std::any_of(one.energy_log.begin(), one.energy_log.end(), [](float e) { return e > 1e-6f; });
  EXPECT_TRUE(touched);
}

}  // namespace
}  // namespace phaco
