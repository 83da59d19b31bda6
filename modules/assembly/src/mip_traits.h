#pragma once
// CGAL MixedIntegerProgramTraits models for COIN-OR CBC (CGAL 5.5 ships none) and for GLPK with a
// time limit (CGAL's own GLPK traits have none). Private to paco::assembly, included by one .cpp.
//
// CGAL's Polygonal_surface_reconstruction::reconstruct() default-constructs its solver, so the
// options reach it through a thread-local MipSettings, and the outcome comes back the same way.
#include <CGAL/Mixed_integer_program_traits.h>

#include <paco/common/child_process.h>

#include "cbc_verdict.h"

#include <Cbc_C_Interface.h>
#include <glpk.h>

#include <algorithm>
#include <chrono>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace paco::detail {

struct MipSettings {
  /// The solve ends by then. Building the program inside CGAL, after the caller set it, takes
  /// seconds on large ones and counts against the budget.
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  bool verbose = false;   ///< let the solver print its log
  /// Run CBC in a child process: a failed assertion inside Clp (seen on degenerate programs)
  /// then fails this solve instead of aborting the caller.
  bool isolate = true;
  /// Values of the first start.size() variables from a known feasible solution, handed to CBC as
  /// a MIP start (empty: none). NaN entries and the variables after them are completed by CBC;
  /// GLPK ignores the start.
  std::vector<double> start;
  /// The caller holds a surface of its own to return when the solve gives none (PolyFit's warm
  /// start): an isolated CBC that runs past its limit is then stopped sooner (see kill grace).
  bool has_fallback = false;

  double secondsLeft() const {
    return std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
  }
};

struct MipOutcome {
  bool optimal = false;
  bool hit_time_limit = false;
  bool has_solution = false;
  std::size_t num_variables = 0, num_constraints = 0;
  std::string message;
};

inline MipSettings& mipSettings() {
  thread_local MipSettings settings;
  return settings;
}
inline MipOutcome& mipOutcome() {
  thread_local MipOutcome outcome;
  return outcome;
}

/// The program in compressed-sparse-column form, shared by both adapters.
template <typename FT>
struct ColumnProgram {
  int num_columns = 0, num_rows = 0;
  std::vector<int> column_start, row_index;
  std::vector<double> value, column_lower, column_upper, objective, row_lower, row_upper;
  std::vector<bool> is_integer;
  bool minimize = true;

  template <typename Traits>
  explicit ColumnProgram(const Traits& program, double infinity) {
    using Variable = typename Traits::Variable;
    using Linear_objective = typename Traits::Linear_objective;
    const auto& variables = program.variables();
    const auto& constraints = program.constraints();
    num_columns = static_cast<int>(variables.size());
    num_rows = static_cast<int>(constraints.size());
    auto bound = [&](FT b) {
      if (b <= -Variable::infinity()) return -infinity;
      if (b >= Variable::infinity()) return infinity;
      return static_cast<double>(b);
    };
    column_lower.resize(num_columns);
    column_upper.resize(num_columns);
    is_integer.resize(num_columns);
    for (int i = 0; i < num_columns; ++i) {
      FT lb, ub;
      variables[i]->get_bounds(lb, ub);
      is_integer[i] = variables[i]->variable_type() != Variable::CONTINUOUS;
      if (variables[i]->variable_type() == Variable::BINARY) {
        lb = 0;
        ub = 1;
      }
      column_lower[i] = bound(lb);
      column_upper[i] = bound(ub);
    }
    // Constraints are stored by row; transpose into columns.
    std::vector<std::vector<std::pair<int, double>>> columns(num_columns);
    row_lower.resize(num_rows);
    row_upper.resize(num_rows);
    for (int r = 0; r < num_rows; ++r) {
      for (const auto& [variable, coefficient] : constraints[r]->coefficients())
        columns[variable->index()].emplace_back(r, static_cast<double>(coefficient));
      FT lb, ub;
      constraints[r]->get_bounds(lb, ub);
      row_lower[r] = bound(lb);
      row_upper[r] = bound(ub);
    }
    column_start.reserve(num_columns + 1);
    column_start.push_back(0);
    for (auto& column : columns) {
      std::sort(column.begin(), column.end());
      for (const auto& [r, v] : column) {
        row_index.push_back(r);
        value.push_back(v);
      }
      column_start.push_back(static_cast<int>(row_index.size()));
    }
    objective.assign(num_columns, 0.0);
    for (const auto& [variable, coefficient] : program.objective()->coefficients())
      objective[variable->index()] = static_cast<double>(coefficient);
    minimize = program.objective()->sense() == Linear_objective::MINIMIZE;
  }
};

/// COIN-OR CBC through its C interface (CbcMain1: presolve, cuts and heuristics as the cbc
/// executable uses them). Stops at MipSettings::seconds and keeps the best solution found.
template <typename FT>
class Cbc_mixed_integer_program_traits : public CGAL::Mixed_integer_program_traits<FT> {
 public:
  using Base = CGAL::Mixed_integer_program_traits<FT>;
  using Variable = typename Base::Variable;

  bool solve() override {
    Base::error_message_.clear();
    MipOutcome& outcome = mipOutcome();
    outcome = MipOutcome{};
    const ColumnProgram<FT> program(*this, DBL_MAX);
    outcome.num_variables = static_cast<std::size_t>(program.num_columns);
    outcome.num_constraints = static_cast<std::size_t>(program.num_rows);

    const MipSettings& settings = mipSettings();
    const double seconds = settings.secondsLeft();  // this solve's budget
    if (seconds <= 0.0) {
      outcome.hit_time_limit = true;
      Base::error_message_ = outcome.message =
          "building the binary program used up the time limit before CBC could start; raise it or use the "
          "cell-complex backend";
      return false;
    }
    CbcRun run;
    if (settings.isolate) {
      // A hard wall-clock bound as well, in case CBC overruns its own limit.
      const auto began = std::chrono::steady_clock::now();
      auto solveInChild = [&](const MipSettings& s, double budget) {
        // CBC checks its limit only between phases (its root LP alone can take seconds). Past it,
        // a late solution is worth waiting for only when the caller has nothing else to return.
        const double grace = s.has_fallback ? std::max(0.5, 0.25 * budget) : std::max(10.0, 0.5 * budget);
        return runInChildProcess([&] { return solveWithCbc(program, s, budget).serialise(); }, budget + grace);
      };
      ChildProcessResult child = solveInChild(settings, seconds);
      if (!child.ok && !child.timed_out && !child.interrupted && !settings.start.empty()) {
        // CBC's MIP-start path trips a Clp assertion on a few programs: solve again without it.
        MipSettings cold = settings;
        cold.start.clear();
        const double left = seconds - std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
        if (left > 0.0) child = solveInChild(cold, left);
      }
      if (!child.ok || !run.deserialise(child.output, program.num_columns)) {
        outcome.hit_time_limit = child.timed_out;
        Base::error_message_ = outcome.message =
            child.interrupted ? "interrupted"
                              : "the MIP solver CBC failed (" + (child.ok ? std::string("garbled result") : child.error) +
                                    "); this case has no solution; --solver glpk may get through";
        return false;
      }
    } else {
      run = solveWithCbc(program, settings, seconds);
    }
    outcome.optimal = run.optimal;
    outcome.hit_time_limit = run.hit_time_limit;
    bool ok = false;
    if (run.has_solution) {
      outcome.has_solution = true;
      Base::result_.resize(program.num_columns);
      for (int i = 0; i < program.num_columns; ++i) {
        double x = run.solution[static_cast<std::size_t>(i)];
        if (program.is_integer[i]) x = std::round(x);
        Base::variables_[i]->set_solution_value(x);
        Base::result_[i] = x;
      }
      ok = true;
    } else if (run.infeasible) {
      outcome.message = "CBC: the binary program is infeasible";
    } else if (outcome.hit_time_limit) {
      outcome.message = "CBC found no feasible solution in the " + std::to_string(seconds) +
                        " s left of the time limit; raise it or use the cell-complex backend";
    } else {
      outcome.message = "CBC stopped without a solution (status " + std::to_string(run.status) +
                        ", secondary status " + std::to_string(run.secondary_status) + ")";
    }
    Base::error_message_ = outcome.message;
    return ok;
  }

 private:
  // What one CBC solve found, in a form that crosses a pipe.
  struct CbcRun {
    bool optimal = false, hit_time_limit = false, has_solution = false, infeasible = false;
    int status = 0, secondary_status = 0;
    std::vector<double> solution;

    std::string serialise() const {
      const int header[6] = {optimal, hit_time_limit, has_solution, infeasible, status, secondary_status};
      std::string bytes(sizeof(header) + solution.size() * sizeof(double), '\0');
      std::memcpy(bytes.data(), header, sizeof(header));
      if (!solution.empty()) std::memcpy(bytes.data() + sizeof(header), solution.data(), solution.size() * sizeof(double));
      return bytes;
    }
    bool deserialise(const std::string& bytes, int columns) {
      int header[6];
      if (bytes.size() < sizeof(header)) return false;
      std::memcpy(header, bytes.data(), sizeof(header));
      optimal = header[0] != 0;
      hit_time_limit = header[1] != 0;
      has_solution = header[2] != 0;
      infeasible = header[3] != 0;
      status = header[4];
      secondary_status = header[5];
      const std::size_t expected = has_solution ? static_cast<std::size_t>(columns) : 0;
      if (bytes.size() != sizeof(header) + expected * sizeof(double)) return false;
      solution.resize(expected);
      if (expected) std::memcpy(solution.data(), bytes.data() + sizeof(header), expected * sizeof(double));
      return true;
    }
  };

  static CbcRun solveWithCbc(const ColumnProgram<FT>& program, const MipSettings& settings, double seconds) {
    CbcRun run;
    Cbc_Model* model = Cbc_newModel();
    if (!model) throw std::runtime_error("CBC: cannot create a model");
    const std::vector<CoinBigIndex> column_start(program.column_start.begin(), program.column_start.end());
    Cbc_loadProblem(model, program.num_columns, program.num_rows, column_start.data(), program.row_index.data(),
                    program.value.data(), program.column_lower.data(), program.column_upper.data(),
                    program.objective.data(), program.row_lower.data(), program.row_upper.data());
    for (int i = 0; i < program.num_columns; ++i)
      if (program.is_integer[i]) Cbc_setInteger(model, i);
    Cbc_setObjSense(model, program.minimize ? 1.0 : -1.0);
    Cbc_setMaximumSeconds(model, std::max(0.01, seconds));
    Cbc_setLogLevel(model, settings.verbose ? 1 : 0);
    if (!settings.verbose) Cbc_setParameter(model, "log", "0");
    if (!settings.start.empty() && settings.start.size() <= static_cast<std::size_t>(program.num_columns)) {
      std::vector<int> columns;
      std::vector<double> values;
      for (std::size_t i = 0; i < settings.start.size(); ++i)
        if (std::isfinite(settings.start[i])) columns.push_back(static_cast<int>(i)), values.push_back(settings.start[i]);
      Cbc_setMIPStartI(model, static_cast<int>(columns.size()), columns.data(), values.data());
    }
    const auto began = std::chrono::steady_clock::now();
    Cbc_solve(model);
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    const double* best = Cbc_bestSolution(model);
    run.optimal = Cbc_isProvenOptimal(model) != 0;
    const CbcVerdict verdict =
        judgeCbcRun(Cbc_isProvenInfeasible(model) != 0,
                    Cbc_isSecondsLimitReached(model) != 0 || Cbc_secondaryStatus(model) == 4, best != nullptr,
                    elapsed, seconds);
    run.infeasible = verdict.infeasible;
    run.hit_time_limit = verdict.hit_time_limit;
    run.status = Cbc_status(model);
    run.secondary_status = Cbc_secondaryStatus(model);
    if (best) {
      run.has_solution = true;
      run.solution.assign(best, best + program.num_columns);
    }
    Cbc_deleteModel(model);
    return run;
  }
};

/// GLPK's branch-and-cut with a time limit; past it the best integer solution found is kept.
template <typename FT>
class Glpk_timed_mixed_integer_program_traits : public CGAL::Mixed_integer_program_traits<FT> {
 public:
  using Base = CGAL::Mixed_integer_program_traits<FT>;

  bool solve() override {
    Base::error_message_.clear();
    MipOutcome& outcome = mipOutcome();
    outcome = MipOutcome{};
    const ColumnProgram<FT> program(*this, DBL_MAX);
    outcome.num_variables = static_cast<std::size_t>(program.num_columns);
    outcome.num_constraints = static_cast<std::size_t>(program.num_rows);

    glp_prob* lp = glp_create_prob();
    glp_set_obj_dir(lp, program.minimize ? GLP_MIN : GLP_MAX);
    auto bounds_type = [](double lb, double ub) {
      const bool has_lb = lb > -DBL_MAX, has_ub = ub < DBL_MAX;
      if (has_lb && has_ub) return lb == ub ? GLP_FX : GLP_DB;
      if (has_lb) return GLP_LO;
      if (has_ub) return GLP_UP;
      return GLP_FR;
    };
    if (program.num_columns > 0) glp_add_cols(lp, program.num_columns);
    if (program.num_rows > 0) glp_add_rows(lp, program.num_rows);
    for (int r = 0; r < program.num_rows; ++r)
      glp_set_row_bnds(lp, r + 1, bounds_type(program.row_lower[r], program.row_upper[r]), program.row_lower[r],
                       program.row_upper[r]);
    std::vector<int> index(1);
    std::vector<double> value(1);
    for (int c = 0; c < program.num_columns; ++c) {
      glp_set_col_kind(lp, c + 1, program.is_integer[c] ? GLP_IV : GLP_CV);
      glp_set_col_bnds(lp, c + 1, bounds_type(program.column_lower[c], program.column_upper[c]),
                       program.column_lower[c], program.column_upper[c]);
      glp_set_obj_coef(lp, c + 1, program.objective[c]);
      index.resize(1);
      value.resize(1);  // GLPK arrays are 1-based
      for (int k = program.column_start[c]; k < program.column_start[c + 1]; ++k) {
        index.push_back(program.row_index[k] + 1);
        value.push_back(program.value[k]);
      }
      glp_set_mat_col(lp, c + 1, static_cast<int>(index.size()) - 1, index.data(), value.data());
    }
    const MipSettings& settings = mipSettings();
    const double seconds = std::max(0.0, settings.secondsLeft());
    glp_iocp parameters;
    glp_init_iocp(&parameters);
    parameters.msg_lev = settings.verbose ? GLP_MSG_ON : GLP_MSG_OFF;
    parameters.presolve = GLP_ON;
    parameters.tm_lim = static_cast<int>(std::min(2.0e9, std::max(10.0, seconds * 1000.0)));
    const int code = glp_intopt(lp, &parameters);
    const int status = glp_mip_status(lp);
    outcome.hit_time_limit = code == GLP_ETMLIM;
    outcome.optimal = code == 0 && status == GLP_OPT;
    bool ok = false;
    if ((code == 0 || code == GLP_ETMLIM || code == GLP_EMIPGAP) && (status == GLP_OPT || status == GLP_FEAS)) {
      outcome.has_solution = true;
      Base::result_.resize(program.num_columns);
      for (int i = 0; i < program.num_columns; ++i) {
        double x = glp_mip_col_val(lp, i + 1);
        if (program.is_integer[i]) x = std::round(x);
        Base::variables_[i]->set_solution_value(x);
        Base::result_[i] = x;
      }
      ok = true;
    } else if (code == GLP_ETMLIM) {
      outcome.message = "GLPK found no feasible solution in the " + std::to_string(seconds) +
                        " s left of the time limit (try --solver cbc)";
    } else if (status == GLP_NOFEAS || code == GLP_ENOPFS) {
      outcome.message = "GLPK: the binary program is infeasible";
    } else {
      outcome.message = "GLPK failed (glp_intopt code " + std::to_string(code) + ")";
    }
    Base::error_message_ = outcome.message;
    glp_delete_prob(lp);
    return ok;
  }
};

}  // namespace paco::detail
