// The implicit step's choice between its team of two and the calling thread alone
// (systems/deform/team_choice.hpp): trials both ways, then the cheaper, and a retrial that lets a
// change of costs (the host moving the cores) turn the choice.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "systems/deform/team_choice.hpp"

namespace phaco::deform {
namespace {

// Runs `steps` steps of `nodes` nodes whose cost is alone_ns or team_ns per node and iteration;
// returns how many ran on the team.
int run_steps(TeamChoice& choice, uint32_t nodes, int steps, double alone_ns, double team_ns,
              const TeamChoiceRule& rule = {}) {
  int on_team = 0;
  for (int k = 0; k < steps; ++k) {
    const bool team = choose_team(choice, nodes, rule);
    on_team += team;
    record_team_step(choice, nodes, team, team ? team_ns : alone_ns, rule);
  }
  return on_team;
}

TEST(TeamChoice, SmallSetsStayOnTheCallingThreadAndAreNotTimed) {
  TeamChoice choice;
  EXPECT_EQ(run_steps(choice, 255, 100, 10.0, 1.0), 0);
  for (const auto& c : choice.classes) EXPECT_EQ(c.alone.steps + c.team.steps, 0u);
}

TEST(TeamChoice, TriesBothWaysAlternatelyBeforeChoosing) {
  TeamChoice choice;
  const TeamChoiceRule rule;
  std::vector<bool> ways;
  for (uint32_t k = 0; k < 2 * rule.trial_steps; ++k) {
    const bool team = choose_team(choice, 1000, rule);
    ways.push_back(team);
    record_team_step(choice, 1000, team, 1.0, rule);
  }
  EXPECT_EQ(std::count(ways.begin(), ways.end(), true), int(rule.trial_steps));
  for (size_t k = 1; k < ways.size(); ++k) EXPECT_NE(ways[k], ways[k - 1]) << k;
}

TEST(TeamChoice, TakesTheCheaperWayAndRetriesTheOtherNowAndThen) {
  const TeamChoiceRule rule;
  // After the 4 + 4 trials, 1,000 steps: the costlier way is retried after 32, 64, 128 and then
  // every 256 steps (at 32, 96, 224, 480, 736 and 992), the cheaper way every other step.
  const int after_trials = 1000, retrials = 6;
  TeamChoice faster_team;
  EXPECT_EQ(run_steps(faster_team, 1000, 8 + after_trials, 1.0, 0.8, rule),
            4 + after_trials - retrials);
  TeamChoice slower_team;
  EXPECT_EQ(run_steps(slower_team, 1000, 8 + after_trials, 1.0, 1.3, rule), 4 + retrials);
}

TEST(TeamChoice, RetrialsThinOutWhileTheChoiceHolds) {
  const TeamChoiceRule rule;
  TeamChoice choice;
  run_steps(choice, 1000, 2 * int(rule.trial_steps), 1.0, 1.3, rule);
  // The team stays dearer: the waits between its retrials double up to rule.retrial_most.
  std::vector<int> retrial_at;
  for (int k = 1; k <= 1500; ++k) {
    const bool team = choose_team(choice, 1000, rule);
    if (team) retrial_at.push_back(k);
    record_team_step(choice, 1000, team, team ? 1.3 : 1.0, rule);
  }
  const std::vector<int> expected = {32, 96, 224, 480, 736, 992, 1248};
  EXPECT_EQ(retrial_at, expected);
}

TEST(TeamChoice, FollowsAChangeOfCostsBothWays) {
  const TeamChoiceRule rule;
  TeamChoice choice;
  // The team costs 1.3× first (cores far apart) for long enough that the retrials are at their
  // widest, then 0.8× (the host moved them), then 1.3× again.
  run_steps(choice, 2000, 1200, 1.0, 1.3);
  ASSERT_EQ(choice.classes[2].retrial_interval, rule.retrial_most);
  const int near = run_steps(choice, 2000, 400, 1.0, 0.8);
  // The next retrial's low cost turns the choice (at most retrial_most steps in); after the turn
  // the calling thread alone is retried at the short wait again, then less and less often.
  EXPECT_GE(near, 400 - int(rule.retrial_most) - 4) << "one retrial should find the cheaper team";
  EXPECT_LE(near, 400 - 2);
  const int far_again = run_steps(choice, 2000, 100, 1.0, 1.3);
  // The team keeps its old low costs until they leave its last 8: 8 steps, then retrials.
  EXPECT_LE(far_again, 8 + 100 / 32) << "a costlier team is dropped within a few steps";
}

TEST(TeamChoice, ATurnedChoiceBringsTheShortWaitBack) {
  const TeamChoiceRule rule;
  TeamChoice choice;
  run_steps(choice, 1000, 1200, 1.0, 1.3);  // waits at their widest
  // The team becomes cheaper: the retrial that finds it turns the choice, and the calling
  // thread's own retrial comes rule.retrial_every steps after that, not retrial_most.
  int turned_at = -1, alone_retrial_at = -1;
  for (int k = 1; k <= 600 && alone_retrial_at < 0; ++k) {
    const bool team = choose_team(choice, 1000, rule);
    record_team_step(choice, 1000, team, team ? 0.8 : 1.0, rule);
    if (team && turned_at < 0) turned_at = k;
    if (!team && turned_at >= 0) alone_retrial_at = k;
  }
  ASSERT_GT(turned_at, 0);
  EXPECT_LE(turned_at, int(rule.retrial_most));
  EXPECT_EQ(alone_retrial_at - turned_at, int(rule.retrial_every));
}

TEST(TeamChoice, PreemptedStepsDoNotTurnTheChoice) {
  // Every third team step is preempted (the haptic thread took a core: 5× its cost); the team
  // is still the cheaper way and stays chosen.
  TeamChoice choice;
  int on_team = 0, team_steps = 0;
  for (int k = 0; k < 400; ++k) {
    const bool team = choose_team(choice, 1000);
    on_team += team;
    const double cost = team ? (++team_steps % 3 == 0 ? 4.0 : 0.8) : 1.0;
    record_team_step(choice, 1000, team, cost);
  }
  EXPECT_GT(on_team, 400 - 4 - 400 / 32 - 1);
}

TEST(TeamChoice, SizeClassesAreTimedApart) {
  TeamChoice choice;
  // Small sets: the team loses; large sets: it wins. Each class learns its own.
  run_steps(choice, 300, 100, 1.0, 1.5);
  run_steps(choice, 5000, 100, 1.0, 0.6);
  EXPECT_LT(run_steps(choice, 300, 64, 1.0, 1.5), 4);
  EXPECT_GT(run_steps(choice, 5000, 64, 1.0, 0.6), 60);
}

TEST(TeamChoice, ANonFiniteOrNegativeCostIsIgnored) {
  TeamChoice choice;
  record_team_step(choice, 1000, true, -1.0);
  record_team_step(choice, 1000, true, std::numeric_limits<double>::infinity());
  record_team_step(choice, 1000, false, std::numeric_limits<double>::quiet_NaN());
  for (const auto& c : choice.classes) EXPECT_EQ(c.alone.steps + c.team.steps, 0u);
}

}  // namespace
}  // namespace phaco::deform
