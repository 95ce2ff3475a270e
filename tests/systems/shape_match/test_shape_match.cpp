// The shape-matching policy and pass (systems/shape_match/shape_match.hpp): precision paths,
// continuity of the undetermined twist, the goal pull, and the whole-lens pass (parallel,
// bit-identical for 1, 2 and 4 threads, equal to the per-fragment serial loop, no allocation).
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <cstring>
#include <span>
#include <vector>

#include "systems/shape_match/shape_match.hpp"
#include "tests/engine/schedule/alloc_counter.hpp"
#include "tests/systems/shape_match/clouds.hpp"

namespace phaco::shape_match {
namespace {

using test::Gen;

std::span<const Vec3> cs(const std::vector<Vec3>& v) {
  return {v.data(), v.size()};
}

// Every fragment solved in double: the pull tests check the pull law to rounding.
MatchSettings all_double() {
  MatchSettings s;
  s.small_fragment = 1u << 30;
  return s;
}

TEST(ShapeMatch, PathsFollowThePolicy) {
  Gen g(21);
  const Quat prev = g.rotation();
  auto run = [&](const std::vector<Vec3>& a, const Quat& r) {
    return match_fragment<double>(cs(a), cs(test::moved(a, r, Vec3(0.3, 0.1, -0.2))), {}, prev);
  };
  const Quat r = g.rotation();
  const FragmentMatch one = run(test::random_cloud(g, 1), r);
  EXPECT_EQ(one.path, MatchPath::KeepPrevious);
  EXPECT_EQ(one.rotation.coeffs(), prev.coeffs());
  EXPECT_EQ(run(test::random_cloud(g, 2), r).path, MatchPath::Continuous);
  EXPECT_EQ(run(test::line_cloud(g, 30, 0.0), r).path, MatchPath::Continuous);
  const FragmentMatch small = run(test::random_cloud(g, 4), r);
  EXPECT_EQ(small.path, MatchPath::Fast);
  EXPECT_LT(rotation_angle(small.rotation, r), 1e-9);
  const FragmentMatch big = run(test::random_cloud(g, 200), r);
  EXPECT_EQ(big.path, MatchPath::Fast);
  EXPECT_LT(rotation_angle(big.rotation, r), 1e-9);
  // Nearly collinear: the quartic is not trusted there, Eigen in double decides and is right.
  const FragmentMatch thin = run(test::line_cloud(g, 50, 1e-4), r);
  EXPECT_EQ(thin.path, MatchPath::Exact);
  EXPECT_LT(rotation_angle(thin.rotation, r), 1e-5);
  // A float first attempt: taken for a large well-spread fragment, never for a small one, and
  // refused (falling back to double) for the nearly collinear one.
  MatchSettings with_float;
  with_float.first_precision = Precision::Float;
  const auto cloud = test::random_cloud(g, 200);
  const auto moved = test::moved(cloud, r, Vec3::Zero());
  const FragmentMatch f = match_fragment<double>(cs(cloud), cs(moved), {}, prev, with_float);
  EXPECT_EQ(f.path, MatchPath::Fast);
  EXPECT_LT(rotation_angle(f.rotation, r), 1e-4);
  const auto thin_cloud = test::line_cloud(g, 50, 1e-4);
  const FragmentMatch tf = match_fragment<double>(
      cs(thin_cloud), cs(test::moved(thin_cloud, r, Vec3::Zero())), {}, prev, with_float);
  EXPECT_EQ(tf.path, MatchPath::Exact);
  EXPECT_LT(rotation_angle(tf.rotation, r), 1e-5);
  // The result stays in the previous quaternion's hemisphere.
  EXPECT_GE(big.rotation.dot(prev), 0.0);
}

// Random fragments of 1..1000 cells through the policy: always a unit quaternion, within 1e-5 rad
// of the truth wherever the rotation is determined.
TEST(ShapeMatch, PolicyRecoversDeterminedRotations) {
  Gen g(22);
  for (int n : {1, 2, 3, 5, 9, 33, 100, 1000}) {
    for (int trial = 0; trial < (n >= 100 ? 5 : 30); ++trial) {
      const auto a = test::random_cloud(g, n);
      const Quat r = g.rotation();
      const auto m = test::random_masses(g, a.size());
      const FragmentMatch f = match_fragment<double>(cs(a), cs(test::moved(a, r, g.in_box(3))),
                                                     {m.data(), m.size()}, g.rotation());
      EXPECT_NEAR(f.rotation.norm(), 1.0, 1e-12);
      if (f.path == MatchPath::Fast || f.path == MatchPath::Exact) {
        EXPECT_LT(rotation_angle(f.rotation, r), 1e-5) << "n=" << n;
      }
      if (n >= 3) {
        EXPECT_NE(f.path, MatchPath::Continuous) << "random cloud of " << n;
      }
    }
  }
}

// A collinear fragment swung smoothly over 100 frames (2° per frame, and a twist about its own line
// the data cannot see): the continuous choice never jumps more than the true step, maps the line
// right, and puts every goal on its cell.
TEST(ShapeMatch, CollinearFragmentRotatesContinuously) {
  Gen g(23);
  const auto a = test::line_cloud(g, 6, 0.0);
  const Vec3 line = (a[1] - a[0]).normalized();
  const Vec3 axis = line.cross(g.unit()).normalized();
  const double step = 2.0 * M_PI / 180;
  Quat prev = Quat::Identity();
  double worst_jump = 0, raw_worst_jump = 0;
  Quat raw_prev = Quat::Identity();
  for (int frame = 1; frame <= 100; ++frame) {
    const Quat truth = Quat(Eigen::AngleAxisd(frame * step, axis)) *
                       Quat(Eigen::AngleAxisd(0.05 * frame, line));  // twist: invisible
    const auto b = test::moved(a, truth, Vec3(0.01 * frame, 0, 0));
    const FragmentMatch f = match_fragment<double>(cs(a), cs(b), {}, prev);
    ASSERT_EQ(f.path, MatchPath::Continuous);
    worst_jump = std::max(worst_jump, rotation_angle(prev, f.rotation));
    EXPECT_LT((f.rotation * line - truth * line).norm(), 1e-9);
    for (size_t i = 0; i < a.size(); ++i) EXPECT_LT((goal_position(f, a[i]) - b[i]).norm(), 1e-9);
    prev = f.rotation;
    const HornResult<double> raw = horn<double, double>(cs(a), cs(b), {});
    raw_worst_jump = std::max(raw_worst_jump, rotation_angle(raw_prev, raw.rotation));
    raw_prev = raw.rotation;
  }
  EXPECT_LE(worst_jump, step + 1e-9);
  RecordProperty("raw_horn_worst_jump_deg", std::to_string(raw_worst_jump * 180 / M_PI));
}

// α = 1 puts a deformed fragment on its rigid fit (pairwise distances = rest distances) and leaves
// a rigidly moved one exactly where it is.
TEST(ShapeMatch, FullPullRestoresTheRestShape) {
  Gen g(24);
  const auto a = test::random_cloud(g, 12);
  const Quat r = g.rotation();
  const auto rigid = test::moved(a, r, g.in_box(2));
  std::vector<Vec3> x = rigid;
  FragmentMatch f = match_fragment<double>(cs(a), cs(x), {}, Quat::Identity(), all_double());
  pull_to_goals<double>(f, cs(a), {x.data(), x.size()}, 1.0);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_LT((x[i] - rigid[i]).norm(), 1e-12);
  // The default policy (quartic in double): the same to rounding.
  std::vector<Vec3> y = rigid;
  pull_to_goals<double>(match_fragment<double>(cs(a), cs(y), {}, Quat::Identity()), cs(a),
                        {y.data(), y.size()}, 1.0);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_LT((y[i] - rigid[i]).norm(), 1e-12);

  for (Vec3& p : x) p += 0.2 * g.in_box(1);
  f = match_fragment<double>(cs(a), cs(x), {}, f.rotation, all_double());
  pull_to_goals<double>(f, cs(a), {x.data(), x.size()}, 1.0);
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = i + 1; j < a.size(); ++j)
      EXPECT_NEAR((x[i] - x[j]).norm(), (a[i] - a[j]).norm(), 1e-12);
}

// α < 1: the rigid fit does not move, and the distance to it shrinks by exactly (1 − α) per pull.
TEST(ShapeMatch, PartialPullConvergesGeometrically) {
  Gen g(25);
  const auto a = test::random_cloud(g, 20);
  auto x = test::moved(a, g.rotation(), g.in_box(2));
  for (Vec3& p : x) p += 0.3 * g.in_box(1);
  for (double alpha : {0.1, 0.5, 0.9}) {
    auto y = x;
    const FragmentMatch first =
        match_fragment<double>(cs(a), cs(y), {}, Quat::Identity(), all_double());
    auto distance = [&] {
      double d = 0;
      for (size_t i = 0; i < a.size(); ++i) d += (goal_position(first, a[i]) - y[i]).squaredNorm();
      return std::sqrt(d);
    };
    double before = distance();
    Quat q = first.rotation;
    for (int k = 0; k < 10; ++k) {
      const FragmentMatch f = match_fragment<double>(cs(a), cs(y), {}, q, all_double());
      EXPECT_LT(rotation_angle(f.rotation, first.rotation), 1e-9);
      pull_to_goals<double>(f, cs(a), {y.data(), y.size()}, alpha);
      q = f.rotation;
      const double after = distance();
      EXPECT_NEAR(after / before, 1 - alpha, 1e-6) << "alpha=" << alpha << " pull " << k;
      before = after;
    }
  }
}

// A lens of fragments of every kind: one large fragment (parallel moments), many small ones,
// pairs, singles and a collinear one; current positions moved rigidly per fragment plus noise.
struct LensCase {
  std::vector<Vec3f> rest, current;
  std::vector<float> mass;
  std::vector<uint32_t> offsets{0}, cells;
  std::vector<Quat> rotations;
};

LensCase make_lens_case() {
  Gen g(26);
  LensCase c;
  auto add_fragment = [&](const std::vector<Vec3>& a) {
    const Quat r = g.rotation();
    const Vec3 t = g.in_box(1);
    for (const Vec3& p : a) {
      c.cells.push_back(static_cast<uint32_t>(c.rest.size()));
      c.rest.push_back(p.cast<float>());
      c.current.push_back((r * p + t + 0.01 * g.in_box(1)).cast<float>());
      c.mass.push_back(static_cast<float>(g.uniform(0.5, 2)));
    }
    c.offsets.push_back(static_cast<uint32_t>(c.cells.size()));
    c.rotations.push_back(g.rotation());
  };
  add_fragment(test::random_cloud(g, kParallelCells + 3000));
  for (int k = 0; k < 300; ++k) add_fragment(test::random_cloud(g, 1 + k % 40));
  add_fragment(test::line_cloud(g, 10, 0.0));
  add_fragment(test::line_cloud(g, 12, 1e-4));
  // Interleave cell ids so fragments are not contiguous in memory.
  std::vector<uint32_t> perm(c.rest.size());
  for (uint32_t i = 0; i < perm.size(); ++i)
    perm[i] = static_cast<uint32_t>((uint64_t{i} * 7919) % perm.size());
  LensCase p = c;
  for (uint32_t i = 0; i < perm.size(); ++i) {
    p.rest[perm[i]] = c.rest[i];
    p.current[perm[i]] = c.current[i];
    p.mass[perm[i]] = c.mass[i];
  }
  for (uint32_t& id : p.cells) id = perm[id];
  return p;
}

LensPassStats run_lens(LensCase& c, int threads) {
  tbb::task_arena arena(threads);
  LensPassStats s;
  MatchSettings settings;
  settings.stiffness = 0.7;
  arena.execute([&] {
    s = match_lens<float>({c.rest.data(), c.rest.size()}, {c.current.data(), c.current.size()},
                          {c.mass.data(), c.mass.size()}, FragmentList{c.offsets, c.cells},
                          {c.rotations.data(), c.rotations.size()}, settings);
  });
  return s;
}

TEST(ShapeMatch, LensPassIsBitIdenticalForOneTwoFourThreads) {
  const LensCase base = make_lens_case();
  ASSERT_NE(base.rest.size() % 7919, 0u);  // the interleaving is a permutation
  LensCase one = base;
  const LensPassStats s1 = run_lens(one, 1);
  EXPECT_EQ(s1.fragments, base.offsets.size() - 1);
  EXPECT_EQ(s1.cells, base.rest.size());
  EXPECT_GT(s1.fast, 0u);
  EXPECT_GT(s1.exact, 0u);
  EXPECT_GT(s1.continuous, 0u);
  EXPECT_GT(s1.kept, 0u);
  for (int threads : {2, 4}) {
    LensCase c = base;
    const LensPassStats s = run_lens(c, threads);
    EXPECT_EQ(s.fast, s1.fast);
    EXPECT_EQ(s.continuous, s1.continuous);
    EXPECT_EQ(0,
              std::memcmp(c.current.data(), one.current.data(), c.current.size() * sizeof(Vec3f)))
        << threads << " threads";
    EXPECT_EQ(0, std::memcmp(c.rotations.data(), one.rotations.data(),
                             c.rotations.size() * sizeof(Quat)));
  }
}

// The pass equals matching and pulling each fragment alone (bit-for-bit for the small fragments,
// to rounding for the large one whose moments are reduced in chunks).
TEST(ShapeMatch, LensPassEqualsPerFragmentLoop) {
  LensCase pass = make_lens_case();
  LensCase loop = pass;
  run_lens(pass, 2);
  MatchSettings settings;
  settings.stiffness = 0.7;
  for (size_t f = 0; f + 1 < loop.offsets.size(); ++f) {
    const std::span<const uint32_t> ids(loop.cells.data() + loop.offsets[f],
                                        loop.offsets[f + 1] - loop.offsets[f]);
    const FragmentMatch m = match_fragment<float>(
        {loop.rest.data(), loop.rest.size()}, {loop.current.data(), loop.current.size()},
        {loop.mass.data(), loop.mass.size()}, loop.rotations[f], settings, ids);
    pull_to_goals<float>(m, {loop.rest.data(), loop.rest.size()},
                         {loop.current.data(), loop.current.size()}, settings.stiffness, ids);
    loop.rotations[f] = m.rotation;
    if (ids.size() > kParallelCells) {
      EXPECT_LT(rotation_angle(pass.rotations[f], loop.rotations[f]), 1e-6) << f;
      for (uint32_t id : ids) EXPECT_LT((pass.current[id] - loop.current[id]).norm(), 1e-5f);
    } else {
      EXPECT_EQ(pass.rotations[f].coeffs(), loop.rotations[f].coeffs()) << f;
      for (uint32_t id : ids) EXPECT_EQ(pass.current[id], loop.current[id]) << f;
    }
  }
}

TEST(ShapeMatch, LensPassDoesNotAllocate) {
  if (!phaco::test::allocation_counting_available())
    GTEST_SKIP() << "allocation counting off (ASan)";
  LensCase c = make_lens_case();
  run_lens(c, 1);  // warm-up: TBB's arena and task pools
  tbb::task_arena arena(1);
  long allocations = -1;
  arena.execute([&] {
    phaco::test::start_counting_allocations();
    match_lens<float>({c.rest.data(), c.rest.size()}, {c.current.data(), c.current.size()},
                      {c.mass.data(), c.mass.size()}, FragmentList{c.offsets, c.cells},
                      {c.rotations.data(), c.rotations.size()});
    phaco::test::stop_counting_allocations();
    allocations = phaco::test::allocations_counted();
  });
  EXPECT_EQ(allocations, 0);
}

}  // namespace
}  // namespace phaco::shape_match
