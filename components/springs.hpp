#pragma once
// Springs of a mass-spring body: one per mesh edge. 16 bytes per spring in the hot columns
// (target ≤ 16, issue 3).
//
// Order matters: springs are sorted by their lower particle index and grouped into SpringBlocks,
// so the force pass can run in parallel without atomics and still sum in a fixed order.
#include <cstdint>
#include <vector>

#include "engine/core/table.hpp"

namespace phaco {

// Seed 000 §5.1: F = k·|x|²·x̂ with x the extension (quadratic); seeds 001/003: Hooke, F = k·x.
enum class SpringLaw : uint8_t { Linear, Quadratic };

// Seed 000 §5.1: k(i,j) = (a1 + a2)/l², a1, a2 the areas of the edge's two triangles; or the
// same k for every spring.
enum class StiffnessWeighting : uint8_t { AreaWeighted, Uniform };

struct Springs {
  SlotIndex slots;
  std::vector<uint32_t> i, j;        // particle indices, i < j
  std::vector<float> rest_length;    // mm
  std::vector<float> stiffness;      // Linear: mN/mm; Quadratic: mN/mm²

  template <class F>
  void for_each_column(F&& f) {
    f(i), f(j), f(rest_length), f(stiffness);
  }
};

// A partition of particles into contiguous index ranges ("blocks") such that every spring joins
// a particle of its own block to one of the same or the next block. The force pass then does all
// even blocks in parallel, then all odd blocks: two blocks running together never touch the same
// particle. The partition depends on the mesh only, never on the thread count, so the order in
// which forces are summed on a particle — hence every bit of the result — is fixed.
struct SpringBlocks {
  std::vector<uint32_t> particle_begin;  // size blocks + 1; block b owns [particle_begin[b], particle_begin[b+1])
  std::vector<uint32_t> spring_begin;    // size blocks + 1; springs of block b: [spring_begin[b], spring_begin[b+1])

  uint32_t count() const { return particle_begin.empty() ? 0 : static_cast<uint32_t>(particle_begin.size() - 1); }
};

// CSR adjacency of the spring graph, built once per topology (systems/springs: build_spring_graph;
// rebuild after a cut or tear). Neighbours of particle p: neighbour[offset[p] .. offset[p+1]),
// sorted by particle index; spring[k] is the spring joining p to neighbour[k]. The active node
// set and force propagation walk it breadth-first.
struct SpringGraph {
  std::vector<uint32_t> offset;     // particle_count + 1
  std::vector<uint32_t> neighbour;  // 2 × live springs
  std::vector<uint32_t> spring;     // 2 × live springs

  uint32_t particle_count() const { return offset.empty() ? 0 : static_cast<uint32_t>(offset.size() - 1); }
};

// Per-particle force accumulator, mN; scratch rebuilt every step.
struct Forces {
  std::vector<float> fx, fy, fz;

  void resize_zero(size_t n) {
    fx.assign(n, 0.0f);
    fy.assign(n, 0.0f);
    fz.assign(n, 0.0f);
  }
};

}  // namespace phaco
