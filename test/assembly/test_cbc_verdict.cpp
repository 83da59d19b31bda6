// The rule that turns CBC's flags into what a solve proved (src/cbc_verdict.h).
#include "cbc_verdict.h"

#include <gtest/gtest.h>

namespace {

using paco::detail::judgeCbcRun;

TEST(CbcVerdict, InfeasibleWithTimeLeftIsAProof) {
  const auto verdict = judgeCbcRun(/*proven_infeasible=*/true, /*limit_reached=*/false, /*has_solution=*/false,
                                   /*elapsed=*/0.2, /*budget=*/10.0);
  EXPECT_TRUE(verdict.infeasible);
  EXPECT_FALSE(verdict.hit_time_limit);
}

TEST(CbcVerdict, InfeasibleWithTheTimeUsedUpIsATimeOut) {
  for (const double elapsed : {10.0, 10.3}) {
    const auto verdict = judgeCbcRun(true, false, false, elapsed, 10.0);
    EXPECT_FALSE(verdict.infeasible) << "elapsed " << elapsed;
    EXPECT_TRUE(verdict.hit_time_limit) << "elapsed " << elapsed;
  }
}

TEST(CbcVerdict, ASolutionInHandKeepsCbcsFlags) {
  // CBC never reports a solution with an infeasible program; if it did, the flags stand as they are.
  const auto verdict = judgeCbcRun(true, true, true, 12.0, 10.0);
  EXPECT_TRUE(verdict.infeasible);
  EXPECT_TRUE(verdict.hit_time_limit);
}

TEST(CbcVerdict, ATimeOutWithoutAVerdictStaysATimeOut) {
  const auto verdict = judgeCbcRun(false, true, false, 10.0, 10.0);
  EXPECT_FALSE(verdict.infeasible);
  EXPECT_TRUE(verdict.hit_time_limit);
  const auto solved = judgeCbcRun(false, false, true, 0.5, 10.0);
  EXPECT_FALSE(solved.infeasible);
  EXPECT_FALSE(solved.hit_time_limit);
}

}  // namespace
