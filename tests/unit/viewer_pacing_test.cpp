// Real-time pacing of `torsion view` (demos/viewer/pacing.h): steps per frame and the HUD's
// real-time factor for given dt, frame time and step cost. Binary fractions (1/64 s, ...) keep
// every expected value exact.
#include <gtest/gtest.h>

#include "pacing.h"

namespace torsion::viewer {
namespace {

PacingDecision pace(double dt, double elapsed, double step_cost, double lag = 0,
                    const PacingSettings& settings = {}) {
  PacingInput in;
  in.dt = dt;
  in.elapsed = elapsed;
  in.step_cost = step_cost;
  in.lag = lag;
  return paceFrame(in, settings);
}

TEST(ViewerPacing, SeveralStepsWhenDtIsShorterThanAFrame) {
  const PacingDecision d = pace(1.0 / 256, 1.0 / 64, 1.0 / 4096);
  EXPECT_EQ(d.steps, 4);
  EXPECT_EQ(d.lag, 0.0);
  EXPECT_EQ(d.real_time_factor, 1.0);
  EXPECT_FALSE(d.behind);
}

TEST(ViewerPacing, APartStepIsOwedToTheNextFrame) {
  const PacingDecision d = pace(1.0 / 128, 1.0 / 64 + 1.0 / 512, 1.0 / 4096);
  EXPECT_EQ(d.steps, 2);
  EXPECT_EQ(d.lag, 1.0 / 512);
  EXPECT_EQ(d.real_time_factor, 1.0);
  EXPECT_FALSE(d.behind);
}

TEST(ViewerPacing, ADtLongerThanAFrameStepsEveryOtherFrame) {
  const PacingDecision first = pace(1.0 / 32, 1.0 / 64, 1.0 / 4096);
  EXPECT_EQ(first.steps, 0);
  EXPECT_EQ(first.lag, 1.0 / 64);
  EXPECT_FALSE(first.behind);
  const PacingDecision second = pace(1.0 / 32, 1.0 / 64, 1.0 / 4096, first.lag);
  EXPECT_EQ(second.steps, 1);
  EXPECT_EQ(second.lag, 0.0);
  EXPECT_EQ(second.real_time_factor, 1.0);
}

TEST(ViewerPacing, RoundOffInTheOwedTimeDoesNotDelayAStep) {
  // 0.006 + 0.004 is 0.01 only up to round-off.
  const PacingDecision d = pace(0.01, 0.004, 1e-4, 0.006);
  EXPECT_EQ(d.steps, 1);
  EXPECT_NEAR(d.lag, 0.0, 1e-17);
}

TEST(ViewerPacing, StepsThatFitTheFrameBudgetWhenTheMachineFallsBehind) {
  // 64 steps owed; 1/512 s each, so 17 fit in the 1/30 s budget: 17/1024 s in 1/16 s.
  const PacingDecision d = pace(1.0 / 1024, 1.0 / 16, 1.0 / 512);
  EXPECT_EQ(d.steps, 17);
  EXPECT_TRUE(d.behind);
  EXPECT_EQ(d.real_time_factor, 17.0 / 64);
  EXPECT_EQ(d.lag, 0.0);  // given up, not owed: no backlog
  EXPECT_EQ(realTimeNote(d.real_time_factor), "0.27x REAL TIME");
}

TEST(ViewerPacing, OneStepAFrameWhenOneStepCostsMoreThanTheBudget) {
  const PacingDecision d = pace(1.0 / 64, 1.0 / 4, 1.0 / 16);
  EXPECT_EQ(d.steps, 1);
  EXPECT_TRUE(d.behind);
  EXPECT_EQ(d.real_time_factor, 1.0 / 16);
  EXPECT_EQ(d.lag, 0.0);
}

TEST(ViewerPacing, CheapStepsStopAtTheCap) {
  const PacingDecision d = pace(1.0 / 1024, 1.0 / 16, 1e-6);
  EXPECT_EQ(d.steps, 32);
  EXPECT_TRUE(d.behind);
  EXPECT_EQ(d.real_time_factor, 0.5);
  PacingSettings settings;
  settings.max_steps_per_frame = 4;
  settings.frame_budget = 1;
  const PacingDecision capped = pace(1.0 / 1024, 1.0 / 16, 1e-6, 0, settings);
  EXPECT_EQ(capped.steps, 4);
  EXPECT_EQ(capped.real_time_factor, 1.0 / 16);
}

TEST(ViewerPacing, OneStepWhileItsCostIsUnknown) {
  const PacingDecision d = pace(1.0 / 256, 1.0 / 64, 0);
  EXPECT_EQ(d.steps, 1);
  EXPECT_TRUE(d.behind);
  EXPECT_EQ(d.real_time_factor, 0.25);
}

TEST(ViewerPacing, NoStepsWithoutTimeOrDt) {
  EXPECT_EQ(pace(0.01, 0, 1e-3).steps, 0);
  EXPECT_EQ(pace(0, 1.0 / 64, 1e-3).steps, 0);
  EXPECT_EQ(pace(0.01, -1, 1e-3).steps, 0);
}

TEST(ViewerPacing, TheHudNote) {
  EXPECT_EQ(realTimeNote(1.0), "REAL TIME");
  EXPECT_EQ(realTimeNote(0.96), "REAL TIME");
  EXPECT_EQ(realTimeNote(1.04), "REAL TIME");
  EXPECT_EQ(realTimeNote(0.4), "0.4x REAL TIME");
  EXPECT_EQ(realTimeNote(0.0123), "0.012x REAL TIME");
  EXPECT_EQ(realTimeNote(3.2), "3.2x REAL TIME");
  EXPECT_EQ(realTimeNote(0), "0x REAL TIME");
}

}  // namespace
}  // namespace torsion::viewer
