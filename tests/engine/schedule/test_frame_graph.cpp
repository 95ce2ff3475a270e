#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "engine/schedule/frame_graph.hpp"
#include "tests/engine/schedule/random_systems.hpp"

namespace phaco {
namespace {

SystemDesc sys(std::string name, Phase phase, std::vector<std::string> reads,
               std::vector<std::string> writes, std::vector<std::string> after = {},
               bool barrier = false) {
  SystemDesc s;
  s.name = std::move(name);
  s.phase = phase;
  s.reads = std::move(reads);
  s.writes = std::move(writes);
  s.after = std::move(after);
  s.barrier = barrier;
  s.run = [](const FrameContext&) {};
  return s;
}

size_t idx(const FrameGraph& g, std::string_view name) {
  const size_t i = g.find(name);
  EXPECT_LT(i, g.size()) << "no system " << name;
  return i;
}

bool reaches(const FrameGraph& g, std::string_view a, std::string_view b) {
  return g.reaches(idx(g, a), idx(g, b));
}

bool ordered(const FrameGraph& g, std::string_view a, std::string_view b) {
  return g.ordered(idx(g, a), idx(g, b));
}

std::string message_of(std::vector<SystemDesc> systems) {
  try {
    FrameGraph g(std::move(systems));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no exception)";
}

TEST(FrameGraph, WriterOrdersAfterEarlierReadersAndWriters) {
  const FrameGraph g(
      {sys("read_a", Phase::Dynamics, {"x"}, {}), sys("read_b", Phase::Dynamics, {"x"}, {}),
       sys("write_c", Phase::Dynamics, {}, {"x"}), sys("write_d", Phase::Dynamics, {}, {"x"})});
  EXPECT_TRUE(reaches(g, "read_a", "write_c"));
  EXPECT_TRUE(reaches(g, "read_b", "write_c"));
  EXPECT_TRUE(reaches(g, "write_c", "write_d"));
  EXPECT_FALSE(reaches(g, "write_c", "read_a"));
  EXPECT_FALSE(ordered(g, "read_a", "read_b"));  // readers of one component may run together
}

TEST(FrameGraph, ReadersOrderAfterEarlierWriterAndStayConcurrent) {
  const FrameGraph g({sys("write", Phase::Dynamics, {}, {"x"}),
                      sys("read_1", Phase::Dynamics, {"x"}, {"y"}),
                      sys("read_2", Phase::Dynamics, {"x"}, {"z"})});
  EXPECT_TRUE(reaches(g, "write", "read_1"));
  EXPECT_TRUE(reaches(g, "write", "read_2"));
  EXPECT_FALSE(ordered(g, "read_1", "read_2"));
}

TEST(FrameGraph, DisjointAccessIsUnorderedAcrossPhases) {
  const FrameGraph g({sys("device", Phase::Input, {}, {"tools.pose"}),
                      sys("score", Phase::Metrics, {"metrics.events"}, {"metrics.score"})});
  EXPECT_FALSE(ordered(g, "device", "score"));
  EXPECT_TRUE(g.successors()[0].empty());
  EXPECT_TRUE(g.successors()[1].empty());
}

TEST(FrameGraph, PhaseDecidesWhichSystemIsEarlier) {
  // Registered first but in a later phase: the contacts system is the earlier one.
  const FrameGraph g({sys("integrate", Phase::Dynamics, {}, {"capsule.particles"}),
                      sys("broadphase", Phase::Contacts, {"capsule.particles"}, {"contacts"}),
                      sys("springs", Phase::Dynamics, {"capsule.particles"}, {"capsule.forces"})});
  ASSERT_EQ(g.size(), 3u);
  EXPECT_EQ(g.system(0).name, "broadphase");
  EXPECT_EQ(g.system(1).name, "integrate");  // registration order kept within a phase
  EXPECT_EQ(g.system(2).name, "springs");
  EXPECT_TRUE(reaches(g, "broadphase", "integrate"));  // writer after earlier reader
  EXPECT_TRUE(reaches(g, "integrate", "springs"));     // reader after earlier writer
  EXPECT_FALSE(reaches(g, "integrate", "broadphase"));
}

TEST(FrameGraph, BarrierOrdersEverythingAroundIt) {
  const FrameGraph g({sys("a", Phase::Input, {}, {"a"}), sys("b", Phase::Input, {}, {"b"}),
                      sys("sync", Phase::Topology, {}, {}, {}, true),
                      sys("c", Phase::Dynamics, {}, {"c"}), sys("d", Phase::Metrics, {}, {"d"})});
  EXPECT_FALSE(ordered(g, "a", "b"));
  EXPECT_FALSE(ordered(g, "c", "d"));
  for (const char* before : {"a", "b"}) {
    EXPECT_TRUE(reaches(g, before, "sync")) << before;
    for (const char* after : {"c", "d"}) EXPECT_TRUE(reaches(g, before, after)) << before << after;
  }
  EXPECT_TRUE(reaches(g, "sync", "c"));
  EXPECT_TRUE(reaches(g, "sync", "d"));
}

TEST(FrameGraph, AfterAddsOrderingEvenAgainstPhase) {
  const FrameGraph g(
      {sys("a", Phase::Dynamics, {}, {"a"}), sys("b", Phase::Dynamics, {}, {"b"}, {"a"}),
       sys("late", Phase::Metrics, {}, {"m"}), sys("early", Phase::Input, {}, {"i"}, {"late"})});
  EXPECT_TRUE(reaches(g, "a", "b"));
  EXPECT_TRUE(reaches(g, "late", "early"));  // explicit order may point backwards if acyclic
  EXPECT_FALSE(ordered(g, "a", "late"));
}

TEST(FrameGraph, SuccessorsAreTransitivelyReducedWithReasons) {
  const FrameGraph g({sys("a", Phase::Dynamics, {}, {"x"}), sys("b", Phase::Dynamics, {"x"}, {"y"}),
                      sys("c", Phase::Dynamics, {"x", "y"}, {})});
  const size_t a = idx(g, "a"), b = idx(g, "b"), c = idx(g, "c");
  ASSERT_EQ(g.successors()[a], std::vector<uint32_t>{static_cast<uint32_t>(b)});  // a -> c implied
  ASSERT_EQ(g.successors()[b], std::vector<uint32_t>{static_cast<uint32_t>(c)});
  EXPECT_EQ(g.edge_reasons()[a][0], "x");
  EXPECT_EQ(g.edge_reasons()[b][0], "y");
  EXPECT_TRUE(g.reaches(a, c));
  EXPECT_EQ(g.predecessor_counts(), (std::vector<uint32_t>{0, 1, 1}));
}

TEST(FrameGraph, EveryConflictingPairIsOrderedInRandomGraphs) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    auto systems = test::random_systems(40, 8, seed, seed % 2 == 0);
    for (auto& s : systems) s.run = [](const FrameContext&) {};
    const FrameGraph g(systems);
    EXPECT_TRUE(g.write_conflicts().empty()) << "seed " << seed;
    for (size_t i = 0; i < g.size(); ++i) {
      for (size_t j = i + 1; j < g.size(); ++j) {
        const auto& si = g.system(i);
        const auto& sj = g.system(j);
        auto touches = [](const std::vector<std::string>& list, const std::string& c) {
          return std::find(list.begin(), list.end(), c) != list.end();
        };
        bool race = false;
        for (const auto& c : si.writes) race |= touches(sj.writes, c) || touches(sj.reads, c);
        for (const auto& c : si.reads) race |= touches(sj.writes, c);
        if (race) {
          EXPECT_TRUE(g.reaches(i, j)) << si.name << " / " << sj.name << " seed " << seed;
        }
        EXPECT_FALSE(g.reaches(j, i));  // sorted order is a topological order without 'after'
      }
    }
  }
}

TEST(FrameGraph, DetectorFindsUnorderedWriters) {
  const std::vector<SystemDesc> systems = {sys("cut", Phase::Topology, {}, {"capsule.triangles"}),
                                           sys("tear", Phase::Topology, {}, {"capsule.triangles"}),
                                           sys("integrate", Phase::Dynamics, {}, {"capsule.x"})};
  const auto none = [](size_t, size_t) { return false; };
  const auto conflicts = find_write_conflicts(systems, none);
  ASSERT_EQ(conflicts.size(), 1u);
  EXPECT_EQ(conflicts[0], (std::pair<size_t, size_t>{0, 1}));
  const auto cut_then_tear = [](size_t a, size_t b) { return a == 0 && b == 1; };
  EXPECT_TRUE(find_write_conflicts(systems, cut_then_tear).empty());
  const auto tear_then_cut = [](size_t a, size_t b) { return a == 1 && b == 0; };
  EXPECT_TRUE(find_write_conflicts(systems, tear_then_cut).empty());
  // The same pair inside a real graph gets ordered, so the graph reports nothing.
  const FrameGraph g(systems);
  EXPECT_TRUE(reaches(g, "cut", "tear"));
  EXPECT_TRUE(g.write_conflicts().empty());
}

TEST(FrameGraph, CycleIsRejectedWithItsPath) {
  // a writes what b reads (a -> b); a also asks to run after b (b -> a).
  const std::string two =
      message_of({sys("a", Phase::Input, {}, {"x"}, {"b"}), sys("b", Phase::Dynamics, {"x"}, {})});
  EXPECT_NE(two.find("cycle"), std::string::npos) << two;
  EXPECT_NE(two.find("a -> b -> a"), std::string::npos) << two;

  const std::string three = message_of(
      {sys("a", Phase::Input, {}, {"x"}, {"c"}), sys("b", Phase::Contacts, {"x"}, {"y"}),
       sys("c", Phase::Dynamics, {"y"}, {}), sys("bystander", Phase::Metrics, {"y"}, {})});
  EXPECT_NE(three.find("a -> b -> c -> a"), std::string::npos) << three;
  EXPECT_EQ(three.find("bystander"), std::string::npos) << three;

  const std::string self = message_of({sys("a", Phase::Input, {}, {}, {"a"})});
  EXPECT_NE(self.find("a -> a"), std::string::npos) << self;

  // A barrier plus a backward 'after' closes a loop too.
  const std::string barrier = message_of({sys("a", Phase::Input, {}, {}, {"z"}),
                                          sys("sync", Phase::Topology, {}, {}, {}, true),
                                          sys("z", Phase::Metrics, {}, {})});
  EXPECT_NE(barrier.find("a -> sync -> z -> a"), std::string::npos) << barrier;
}

TEST(FrameGraph, BadDescriptionsAreRejectedByName) {
  const std::string unknown = message_of({sys("integrate", Phase::Dynamics, {}, {}, {"forcez"})});
  EXPECT_NE(unknown.find("'integrate'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("'forcez'"), std::string::npos) << unknown;

  const std::string dup =
      message_of({sys("springs", Phase::Dynamics, {}, {}), sys("springs", Phase::Metrics, {}, {})});
  EXPECT_NE(dup.find("'springs'"), std::string::npos) << dup;
  EXPECT_NE(dup.find("unique"), std::string::npos) << dup;

  EXPECT_NE(message_of({sys("", Phase::Input, {}, {})}).find("empty name"), std::string::npos);

  SystemDesc no_run = sys("idle", Phase::Input, {}, {});
  no_run.run = nullptr;
  const std::string missing = message_of({no_run});
  EXPECT_NE(missing.find("'idle'"), std::string::npos) << missing;
  EXPECT_NE(missing.find("run function"), std::string::npos) << missing;

  const std::string blank = message_of({sys("blank", Phase::Input, {""}, {})});
  EXPECT_NE(blank.find("'blank'"), std::string::npos) << blank;
}

TEST(FrameGraph, EmptyGraphIsValid) {
  const FrameGraph g({});
  EXPECT_EQ(g.size(), 0u);
  EXPECT_TRUE(g.write_conflicts().empty());
  EXPECT_NE(g.to_dot().find("digraph"), std::string::npos);
}

TEST(FrameGraph, DotListsEverySystemAndEdge) {
  auto systems = test::random_systems(25, 6, 3);
  for (auto& s : systems) s.run = [](const FrameContext&) {};
  systems.push_back(sys("say \"hi\"", Phase::Publish, {"c0"}, {}));
  const FrameGraph g(systems);
  const std::string dot = g.to_dot();
  EXPECT_EQ(dot.rfind("digraph", 0), 0u);
  auto id = [](const std::string& name) {
    std::string q = "\"";
    for (char c : name) {
      if (c == '"') q += '\\';
      q += c;
    }
    return q + "\"";
  };
  size_t edges = 0;
  for (size_t p = 0; p < g.size(); ++p) {
    const SystemDesc& s = g.system(p);
    EXPECT_NE(dot.find(id(s.name) + " [label="), std::string::npos) << s.name;
    EXPECT_NE(dot.find("cluster_" + std::string(to_string(s.phase))), std::string::npos);
    for (uint32_t q : g.successors()[p]) {
      ++edges;
      EXPECT_NE(dot.find(id(s.name) + " -> " + id(g.system(q).name)), std::string::npos)
          << s.name << " -> " << g.system(q).name;
    }
  }
  EXPECT_GT(edges, 0u);
  size_t arrows = 0;
  for (size_t at = dot.find("->"); at != std::string::npos; at = dot.find("->", at + 2)) ++arrows;
  EXPECT_EQ(arrows, edges);
}

}  // namespace
}  // namespace phaco
