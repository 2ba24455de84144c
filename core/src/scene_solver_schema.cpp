// The scene file's `solver` object: the keys of SolverOptions, their names (integrators, linear
// solvers, stability rules) and the reference's constraint texts, written from the bounds of
// SolverOptions::validate() so that the two cannot disagree.
#include <string>
#include <vector>

#include "scene_schema.hpp"
#include "tdcr/core/solver_options.hpp"

namespace tdcr::detail {

namespace {

// `solver.integrator`: the names are SolverOptions' own (parse_integrator_kind, to_string), the
// same as the CLI's --integrator and Python's.
template <class T>
Field<T> integrator_field(const char* key, IntegratorKind T::*m, KeyDoc doc) {
  return {{key, "string", doc},
          [m](const json& j, const std::string& p, T& v) {
            if (!j.is_string()) {
              std::vector<const char*> names;
              for (const std::string& n : integrator_names()) names.push_back(n.c_str());
              type_error(p, j, "one of " + quoted_names(names));
            }
            v.*m = parse_integrator_kind(j.get<std::string>(), p);
          },
          [m](const T& v) { return ojson(to_string(v.*m)); },
          {}};
}

const Names<LinearSolverKind> kLinearSolvers = {
    {"auto", LinearSolverKind::Automatic}, {"dense", LinearSolverKind::Dense}, {"klu", LinearSolverKind::SparseKLU}};

// `solver.stability`: "auto", true (always) or false (never).
template <class T>
Field<T> stability_field(const char* key, StabilityCheck T::*m, KeyDoc doc) {
  return {{key, "string or boolean", doc},
          [m](const json& j, const std::string& p, T& v) {
            if (j.is_boolean()) {
              v.*m = j.get<bool>() ? StabilityCheck::Always : StabilityCheck::Never;
              return;
            }
            if (!j.is_string()) type_error(p, j, "\"auto\", true or false");
            if (j.get<std::string>() != "auto") throw InputError(p, text_of(j), "must be \"auto\", true or false");
            v.*m = StabilityCheck::Automatic;
          },
          [m](const T& v) {
            return v.*m == StabilityCheck::Automatic ? ojson("auto") : ojson(v.*m == StabilityCheck::Always);
          },
          {}};
}

// "from 1e-15 to 0.01" as the reference writes numbers.
std::string range_text(double lo, double hi) {
  return "from " + reference_text(ojson(lo)) + " to " + reference_text(ojson(hi));
}

}  // namespace

const Schema<SolverOptions>& solver_schema() {
  constexpr const char* kNewton = "CCsub, PRB, VC, VCref";  // who honours a key
  using S = SolverOptions;
  constexpr const char* kOde = "VC, VCref";
  constexpr const char* kRk4 = "VC, VCref (with `\"rk4_fixed\"`)";
  constexpr const char* kCvode = "VC, VCref (with `\"cvode\"`)";
  // The bounds of SolverOptions::validate(), written from its constants (the Doxygen of
  // SolverOptions justifies them).
  constexpr int kFinest = 1 << S::kMaxRk4Halvings;
  static const std::string rk4_steps = "1 to " + std::to_string(S::kMaxRk4Steps) +
                                       "; minimum RK4 steps per disk interval of the fixed mesh";
  static const std::string rk4_max_step =
      ">= " + reference_text(ojson(S::kMinRk4MaxStep)) +
      "; longest RK4 step of the fixed mesh: a disk interval longer than `rk4_steps` times this takes more steps";
  static const std::string tip_tolerance =
      "0 or " + range_text(S::kMinTipTolerance, S::kMaxTipTolerance) +
      "; accuracy of the tip position: with `\"rk4\"` the mesh is refined from " +
      std::to_string(S::kFirstMeshRk4Steps) + " step per disk interval, h <= " +
      reference_text(ojson(S::kFirstMeshRk4MaxStep)) + " m, until the estimated tip error is at most this (at most " +
      std::to_string(kFinest) + " times the first mesh's steps), and Newton's `function_tolerance` is tied to it; 0: " +
      reference_text(ojson(S::kTipToleranceOverLength)) + " times the robot's length (1e-8 m on the paper robot)";
  static const std::string cvode_rtol = range_text(S::kMinCvodeRtol, S::kMaxCvodeRtol);
  static const std::string cvode_atol = range_text(S::kMinCvodeAtol, S::kMaxCvodeAtol);
  static const std::string function_tolerance =
      "0 or " + range_text(S::kMinFunctionTolerance, S::kMaxFunctionTolerance) +
      "; Newton stops when the scaled residual max-norm is below it; 0: " +
      reference_text(ojson(S::kNewtonPerTipTolerance)) + " times `tip_tolerance` over the robot's length";
  static const std::string step_tolerance =
      range_text(S::kMinStepTolerance, S::kMaxStepTolerance) +
      "; KINSOL's scaled step tolerance (a step-size stop counts as converged only if the residual tolerance holds)";
  static const std::string max_iterations =
      "1 to " + std::to_string(S::kMaxIterations) + "; Newton iterations per solve";
  static const std::string max_continuation_steps =
      "1 to " + std::to_string(S::kMaxContinuationSteps) +
      "; at most this many Newton solves (converged or failed steps)";
  static const Schema<S> s({
      integrator_field("integrator", &S::integrator,
                   {"", nullptr,
                    "`\"rk4\"` (RK4 on a mesh refined until the estimated tip error is within `tip_tolerance`), "
                    "`\"rk4_fixed\"` (RK4 on the fixed mesh of `rk4_steps` and `rk4_max_step`) or `\"cvode\"` "
                    "(SUNDIALS CVODE, Adams, error controlled)",
                    kOde}),
      integer_field("rk4_steps", &S::rk4_steps, {"", nullptr, rk4_steps.c_str(), kRk4}),
      number_field("rk4_max_step", &S::rk4_max_step, {"m", nullptr, rk4_max_step.c_str(), kRk4}),
      number_field("cvode_rtol", &S::cvode_rtol, {"", nullptr, cvode_rtol.c_str(), kCvode}),
      number_field("cvode_atol", &S::cvode_atol, {"state units", nullptr, cvode_atol.c_str(), kCvode}),
      number_field("tip_tolerance", &S::tip_tolerance, {"m", nullptr, tip_tolerance.c_str(), "all models"}),
      number_field("function_tolerance", &S::function_tolerance, {"", nullptr, function_tolerance.c_str(), kNewton}),
      number_field("step_tolerance", &S::step_tolerance, {"", nullptr, step_tolerance.c_str(), kNewton}),
      integer_field("max_iterations", &S::max_iterations, {"", nullptr, max_iterations.c_str(), kNewton}),
      choice_field("linear_solver", &S::linear_solver, kLinearSolvers,
                   {"", nullptr, "`\"auto\"`, `\"dense\"` or `\"klu\"`",
                    "VC, VCref (CCsub and PRB always use dense LU)"}),
      boolean_field("continuation", &S::continuation,
                    {"", nullptr, "follow the loading path from rest when the loads are large or a direct solve fails", kNewton}),
      integer_field("max_continuation_steps", &S::max_continuation_steps,
                    {"", nullptr, max_continuation_steps.c_str(), kNewton}),
      boolean_field("coarse_loading_path", &S::coarse_loading_path,
                    {"", nullptr,
                     "a cold solve that follows the loading path from rest follows it on a coarse RK4 mesh "
                     "(2 steps per disk interval, h <= 4 mm) and solves the answer on the requested mesh "
                     "from its end",
                     "VC, VCref (RK4)"}),
      stability_field("stability", &S::stability,
                      {"", nullptr,
                       "`\"auto\"`, `true` or `false`: which converged answers get their stability decided "
                       "(`stability` in the JSON output, its method `\"not checked\"` where not). `\"auto\"`: "
                       "answers reached by a loading path (from rest, a snap, a warm start's input path), and "
                       "under external loads every cold VCref, CCsub and PRB answer (CCsub and PRB by a sufficient "
                       "test first, without obstacles or tendon friction); not warm steps that follow no path, nor "
                       "other direct solves (VC's test costs more than 25 % of its median loaded solve); `true`: every "
                       "answer; `false`: none. VC by the "
                       "conjugate-point test of the fixed-free rod, CCsub and PRB by the eigenvalues of their "
                       "reduced stiffness, VCref by its reduced stiffness in the disk poses; CC: undetermined "
                       "(docs/models.md, \"Stability\")",
                       "VC, CCsub, PRB, VCref"}),
      boolean_field("reuse_jacobian", &S::reuse_jacobian,
                    {"", nullptr,
                     "a warm start may begin from the previous solve's Jacobian (modified Newton): faster "
                     "trajectories; the answer then depends on the last solve within function_tolerance",
                     "CCsub, PRB, VC, VCref"}),
      boolean_field("extrapolate_warm_starts", &S::extrapolate_warm_starts,
                    {"", nullptr,
                     "a warm start from the workspace's last answer starts from the secant through its last "
                     "two answers when the input moves on along the same line (trajectories)",
                     "CCsub, PRB, VC, VCref"}),
      boolean_field("differential_kinematics", &S::differential_kinematics,
                    {"", nullptr,
                     "compute the tip Jacobian (6 x m, with respect to the actuation values) and the tip "
                     "compliance (6 x 6, with respect to the tip wrench) of every converged answer "
                     "(`tip_jacobian`, `tip_compliance` in the JSON output)",
                     "every model (CC: Jacobian only)"}),
  });
  return s;
}

}  // namespace tdcr::detail
