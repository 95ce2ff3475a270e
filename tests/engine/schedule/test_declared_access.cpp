// The check of declared access against real access (issue 17 item 4): a system that looks up a
// component it did not declare is stopped with a message naming both; declared lookups, constant
// components and unchecked executors pass.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "engine/ecs/world.hpp"
#include "engine/schedule/executor.hpp"
#include "tests/engine/schedule/make_system.hpp"

namespace phaco {
namespace {

struct Positions {
  float x = 0.0f;
};
struct Triangles {
  int count = 3;
};
struct Kind {
  int value = 1;
};
struct Record {
  int frames = 0;
};

struct Fixture {
  World world;
  Entity capsule;
  Entity tool;

  Fixture() {
    world.name_component<Positions>("particles");
    world.name_component<Triangles>("triangles");
    world.name_component<Kind>("kind", AccessKind::Constant);
    world.name_component<Record>("metrics", AccessKind::Global);
    capsule = world.create(EntityKind::Body, "capsule");
    tool = world.create(EntityKind::Tool, "left.forceps");
    world.add(capsule, Positions{});
    world.add(capsule, Triangles{});
    world.add(capsule, Record{});
    world.add(tool, Positions{});
    world.add(tool, Kind{});
  }
};

TEST(DeclaredAccess, NamesFollowTheOwnerAndKind) {
  Fixture f;
  EXPECT_EQ(f.world.access_name<Positions>(f.capsule), "capsule.particles");
  EXPECT_EQ(f.world.access_name<Positions>(f.tool), "tools.particles");
  EXPECT_EQ(f.world.access_name<Record>(f.capsule), "metrics");
  EXPECT_EQ(f.world.access_name<Kind>(f.tool), "");
}

TEST(DeclaredAccess, UndeclaredLookupThrowsNamingSystemAndComponent) {
  Fixture f;
  // Like capsule_dynamics before issue 17: it read the capsule's triangles without saying so.
  FrameGraph graph(
      {test::make_system("capsule_dynamics", {}, {"capsule.particles"}, [&f](const FrameContext&) {
        f.world.at<Positions>(f.capsule).x += 1.0f;
        (void)f.world.at<Triangles>(f.capsule).count;
      })});
  Executor ex(graph, 2, AccessCheck::On);
  try {
    ex.run_frame({});
    FAIL() << "an undeclared lookup was not caught";
  } catch (const std::logic_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'capsule_dynamics'"), std::string::npos) << what;
    EXPECT_NE(what.find("'capsule.triangles'"), std::string::npos) << what;
  }
  // The executor stays usable: the same frame with the check off runs.
  Executor unchecked(graph, 2, AccessCheck::Off);
  EXPECT_NO_THROW(unchecked.run_frame({}));
  EXPECT_EQ(f.world.at<Positions>(f.capsule).x, 2.0f);
}

TEST(DeclaredAccess, DeclaredGlobalAndConstantLookupsPass) {
  Fixture f;
  int ran = 0;
  FrameGraph graph(
      {test::make_system("metrics", {"capsule.particles", "capsule.triangles", "tools.particles"},
                         {"metrics"}, [&](const FrameContext&) {
                           (void)f.world.at<Positions>(f.capsule);
                           (void)f.world.at<Triangles>(f.capsule);
                           (void)f.world.at<Positions>(f.tool);
                           (void)f.world.at<Kind>(f.tool);  // constant: no declaration needed
                           ++f.world.at<Record>(f.capsule).frames;
                           EXPECT_TRUE(f.world.has<Triangles>(f.capsule));  // structure, not data
                           ++ran;
                         })});
  Executor ex(graph, 1, AccessCheck::On);
  for (int i = 0; i < 3; ++i) ex.run_frame({});
  EXPECT_EQ(ran, 3);
  EXPECT_EQ(f.world.at<Record>(f.capsule).frames, 3);
}

TEST(DeclaredAccess, UnnamedComponentTypeIsReported) {
  Fixture f;
  struct Unnamed {
    int v = 0;
  };
  f.world.add(f.capsule, Unnamed{});
  FrameGraph graph(
      {test::make_system("reader", {"capsule.particles"}, {},
                         [&f](const FrameContext&) { (void)f.world.at<Unnamed>(f.capsule); })});
  Executor ex(graph, 1, AccessCheck::On);
  try {
    ex.run_frame({});
    FAIL() << "a lookup of an unnamed component type was not caught";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("no access name"), std::string::npos) << e.what();
  }
}

TEST(DeclaredAccess, OutsideSystemsNothingIsChecked) {
  Fixture f;
  EXPECT_NO_THROW((void)f.world.at<Triangles>(f.capsule));
}

}  // namespace
}  // namespace phaco
