// The mouse's clutch (procedures/trainer/pointer_clutch, issue 24 item 1): the tool follows the
// pointer only between two positions over the view with the clutch key released.
#include <gtest/gtest.h>

#include <cmath>

#include "procedures/trainer/pointer_clutch.hpp"

namespace phaco {
namespace {

TEST(PointerClutch, MotionOnlyBetweenEngagedPositions) {
  PointerClutch c;
  using D = std::array<double, 2>;
  EXPECT_EQ(clutch_step(c, 640, 400, true, false), (D{0, 0})) << "the first position";
  EXPECT_EQ(clutch_step(c, 650, 390, true, false), (D{10, -10}));
  EXPECT_EQ(clutch_step(c, 100, 100, false, false), (D{0, 0})) << "onto a panel";
  EXPECT_EQ(clutch_step(c, 120, 130, false, false), (D{0, 0})) << "over the panel";
  EXPECT_EQ(clutch_step(c, 700, 420, true, false), (D{0, 0})) << "back: no jump";
  EXPECT_EQ(clutch_step(c, 705, 420, true, false), (D{5, 0})) << "then relative motion";
  EXPECT_EQ(clutch_step(c, 900, 100, true, true), (D{0, 0})) << "clutch held: re-centre";
  EXPECT_EQ(clutch_step(c, 640, 400, true, true), (D{0, 0}));
  EXPECT_EQ(clutch_step(c, 640, 400, true, false), (D{0, 0})) << "released where it is";
  EXPECT_EQ(clutch_step(c, 641, 402, true, false), (D{1, 2}));
  EXPECT_EQ(clutch_step(c, NAN, 402, true, false), (D{0, 0})) << "a bad position moves nothing";
  EXPECT_EQ(clutch_step(c, 645, 402, true, false), (D{0, 0}));
}

}  // namespace
}  // namespace phaco
