#pragma once
// What one CBC solve proved, read from CBC's flags. Private to paco::assembly; a header of its
// own so that tests can check the rule without CBC.

namespace paco::detail {

struct CbcVerdict {
  bool infeasible = false;      ///< CBC proved that no solution exists
  bool hit_time_limit = false;  ///< the solve stopped at its time limit
};

/// `proven_infeasible` and `limit_reached` are CBC's own flags; `elapsed` and `budget` are the
/// solve's wall time and its limit, in seconds. When the limit cuts CBC's pre-processing short, its
/// cut generators can report a feasible program infeasible (seen on PolyFit programs, which the
/// empty surface always satisfies): a verdict reached with the time used up and no solution in
/// hand is a time-out, not a proof.
inline CbcVerdict judgeCbcRun(bool proven_infeasible, bool limit_reached, bool has_solution, double elapsed,
                              double budget) {
  CbcVerdict verdict;
  verdict.infeasible = proven_infeasible;
  verdict.hit_time_limit = limit_reached;
  if (proven_infeasible && !has_solution && elapsed >= budget) {
    verdict.infeasible = false;
    verdict.hit_time_limit = true;
  }
  return verdict;
}

}  // namespace paco::detail
