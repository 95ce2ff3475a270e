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
  std::vector<uint32_t> i, j;      // particle indices, i < j
  std::vector<float> rest_length;  // mm
  std::vector<float> stiffness;    // Linear: mN/mm; Quadratic: mN/mm²

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
//
// The planned part is springs [0, tail_begin()): sorted by i when planned. Springs a cut or tear
// adds later are appended after it (the tail, in creation order, any particles) and every block
// pass runs the tail serially after the planned blocks, so the summation order is still fixed.
// A removed spring stays where it is as a tombstone with stiffness 0, so passes that do not test
// liveness add nothing for it. The owner re-plans (compaction, sort, plan_blocks) only when the
// tail and tombstones have grown to a fraction of the table, in a frame without topology change.
struct SpringBlocks {
  std::vector<uint32_t>
      particle_begin;  // size blocks + 1; block b owns [particle_begin[b], particle_begin[b+1])
  std::vector<uint32_t>
      spring_begin;  // size blocks + 1; springs of block b: [spring_begin[b], spring_begin[b+1])

  uint32_t count() const {
    return particle_begin.empty() ? 0 : static_cast<uint32_t>(particle_begin.size() - 1);
  }
  // First spring of the unplanned tail (the planned part's end).
  uint32_t tail_begin() const { return spring_begin.empty() ? 0 : spring_begin.back(); }
};

// Adjacency of the spring graph: per particle a row of (neighbour, spring) pairs sorted by
// neighbour, rows stored one after another with room to grow, so a cut patches the rows of the
// particles it touched instead of rebuilding the graph (systems/springs: build_spring_graph,
// patch_spring_graph). Row p is entries [begin(p), end(p)); a row that outgrows its room moves to
// the end of the arrays (its old room is left unused until the next full build). The active node
// set and force propagation walk it breadth-first.
struct SpringGraph {
  std::vector<uint32_t> row_begin;     // per particle: first entry of its row
  std::vector<uint32_t> row_size;      // per particle: entries in use
  std::vector<uint32_t> row_capacity;  // per particle: entries the row may use where it is
  std::vector<uint32_t> neighbour;     // per entry: the particle across the spring
  std::vector<uint32_t> spring;  // per entry: the spring joining the row's particle to neighbour

  uint32_t particle_count() const { return static_cast<uint32_t>(row_begin.size()); }
  uint32_t begin(uint32_t p) const { return row_begin[p]; }
  uint32_t end(uint32_t p) const { return row_begin[p] + row_size[p]; }
};

// Per-particle force accumulator, mN; scratch rebuilt every step.
struct Forces {
  std::vector<float> fx, fy, fz;

  void resize_zero(size_t n) {
    fx.assign(n, 0.0f);
    fy.assign(n, 0.0f);
    fz.assign(n, 0.0f);
  }
  // New particles get zero force; existing entries are kept (amortised growth after a cut).
  void grow(size_t n) {
    fx.resize(n, 0.0f);
    fy.resize(n, 0.0f);
    fz.resize(n, 0.0f);
  }
};

}  // namespace phaco
