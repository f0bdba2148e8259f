// The ILC safeguard's state machine (IlcSafeguardWatch), one action at a time, on error
// sequences written by hand: lower_q, stop_joint and stop_all, each with the feedforward
// it hands on.
#include <gtest/gtest.h>

#include <vector>

#include "control/iterative_learning.h"

namespace twinsim {
namespace {

// The feedforward of trial k: every entry k, so a column tells which trial it came from.
Eigen::MatrixXd TrialFeedforward(int k) { return Eigen::MatrixXd::Constant(4, 2, k); }

IlcSafeguard WatchGuard() {
  IlcSafeguard g;
  g.growth = 1.1;
  g.cutoff_factor = 0.7;
  g.min_cutoff = 2;
  g.patience = 2;
  g.lowerings = 1;
  return g;
}

// Observes trial k with errors (e0, e1) and feedforward TrialFeedforward(k).
std::vector<IlcSafeguardEvent> SeeTrial(IlcSafeguardWatch* w, int k, double e0, double e1) {
  return w->Observe(k, Eigen::Vector2d(e0, e1), TrialFeedforward(k));
}

TEST(IlcSafeguardWatch, AJointThatGrowsIsLoweredThenStoppedThenEveryJointGoesBack) {
  IlcSafeguardWatch w(WatchGuard(), 4, {10, 10});
  EXPECT_TRUE(SeeTrial(&w, 0, 1.0, 1.0).empty());
  EXPECT_TRUE(SeeTrial(&w, 1, 0.5, 0.5).empty());  // both joints' best, and the arm's
  EXPECT_EQ(w.best_trial(), 1);
  EXPECT_TRUE(SeeTrial(&w, 2, 0.6, 0.4).empty());  // joint 1 above 1.1 x its best: once
  // Twice in a row (patience 2): Q's cutoff lowered, the joint back on its best trial's.
  std::vector<IlcSafeguardEvent> e = SeeTrial(&w, 3, 0.6, 0.3);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].action, "lower_q");
  EXPECT_EQ(e[0].trial, 3);
  EXPECT_EQ(e[0].joint, 0);
  EXPECT_EQ(e[0].best_trial, 1);
  EXPECT_DOUBLE_EQ(e[0].best_rms, 0.5);
  EXPECT_DOUBLE_EQ(e[0].cutoff, 7);
  EXPECT_DOUBLE_EQ(w.cutoffs()[0], 7);
  EXPECT_DOUBLE_EQ(w.cutoffs()[1], 10);
  Eigen::MatrixXd next = w.Next(TrialFeedforward(99));
  EXPECT_EQ(next.col(0), TrialFeedforward(1).col(0));   // joint 1: its best trial's
  EXPECT_EQ(next.col(1), TrialFeedforward(99).col(1));  // joint 2: the learned update
  EXPECT_TRUE(w.learning(0));

  // Growing again after its one lowering: it stops learning and keeps its best.
  EXPECT_TRUE(SeeTrial(&w, 4, 0.6, 0.3).empty());
  e = SeeTrial(&w, 5, 0.6, 0.3);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].action, "stop_joint");
  EXPECT_DOUBLE_EQ(e[0].cutoff, 0);
  EXPECT_FALSE(w.learning(0));
  EXPECT_FALSE(w.stopped());
  next = w.Next(TrialFeedforward(99));
  EXPECT_EQ(next.col(0), TrialFeedforward(1).col(0));
  EXPECT_EQ(next.col(1), TrialFeedforward(99).col(1));
  // The arm's best stays trial 1: its worst joint 0.5 of trial 0's, trials 2 to 5 0.6.
  EXPECT_EQ(w.best_trial(), 1);

  // The stopped joint grows again through the other: every joint back to the arm's best
  // trial, learning ended.
  EXPECT_TRUE(SeeTrial(&w, 6, 0.6, 0.2).empty());
  e = SeeTrial(&w, 7, 0.6, 0.2);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].action, "stop_all");
  EXPECT_EQ(e[0].best_trial, 1);
  EXPECT_TRUE(w.stopped());
  EXPECT_FALSE(w.learning(1));
  EXPECT_EQ(w.Next(TrialFeedforward(99)), TrialFeedforward(1));
  // Nothing more is decided once learning ended.
  EXPECT_TRUE(SeeTrial(&w, 8, 5.0, 5.0).empty());
  EXPECT_TRUE(SeeTrial(&w, 9, 5.0, 5.0).empty());
}

TEST(IlcSafeguardWatch, WithoutRoomToLowerQAJointStopsAtOnce) {
  // Below min_cutoff after one lowering (2.5 x 0.7 < 2), and without a filter Q at all.
  for (const auto& [q_order, cutoff] : {std::pair{4, 2.5}, std::pair{0, 10.0}}) {
    IlcSafeguardWatch w(WatchGuard(), q_order, {cutoff, 10});
    SeeTrial(&w, 0, 1.0, 1.0);
    SeeTrial(&w, 1, 0.5, 0.5);
    SeeTrial(&w, 2, 0.6, 0.5);
    const std::vector<IlcSafeguardEvent> e = SeeTrial(&w, 3, 0.6, 0.5);
    ASSERT_EQ(e.size(), 1u) << "q_order " << q_order;
    EXPECT_EQ(e[0].action, "stop_joint") << "q_order " << q_order;
    EXPECT_FALSE(w.learning(0));
  }
}

TEST(IlcSafeguardWatch, AnErrorWithinTheGrowthOrNotInARowDoesNothing) {
  IlcSafeguardWatch w(WatchGuard(), 4, {10, 10});
  SeeTrial(&w, 0, 1.0, 1.0);
  SeeTrial(&w, 1, 0.5, 0.5);
  EXPECT_TRUE(SeeTrial(&w, 2, 0.54, 0.5).empty());  // within 1.1 x 0.5
  EXPECT_TRUE(SeeTrial(&w, 3, 0.6, 0.5).empty());   // above, once
  EXPECT_TRUE(SeeTrial(&w, 4, 0.54, 0.5).empty());  // back within: the count restarts
  EXPECT_TRUE(SeeTrial(&w, 5, 0.6, 0.5).empty());   // above, once again
  EXPECT_EQ(w.Next(TrialFeedforward(99)), TrialFeedforward(99));
  // No watch at all with growth 0.
  IlcSafeguard off = WatchGuard();
  off.growth = 0;
  IlcSafeguardWatch none(off, 4, {10, 10});
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(SeeTrial(&none, k, k == 0 ? 1.0 : 3.0, 1.0).empty());
}

}  // namespace
}  // namespace twinsim
