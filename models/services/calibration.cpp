// calibrate(): the Ceres problem (one residual block per measurement under the robust loss, one
// parameter block of the scaled parameters with their bounds), its evaluation through a cache
// that an evaluation callback fills once per point (all solves, and the structured differences
// when Ceres asks for Jacobians), and the report (calibration_report.cpp).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include <ceres/ceres.h>
#include <ceres/evaluation_callback.h>

#include "calibration_detail.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr {

namespace calibration_detail {
// calibration_report.cpp: covariance, correlation and identifiability from the final Jacobian.
void fill_report(const Evaluator& evaluator, const Eigen::VectorXd& values, const Eigen::VectorXd& r,
                 const Eigen::MatrixXd& J, bool has_std, const CalibrationOptions& options, CalibrationResult& out);
}  // namespace calibration_detail

namespace {

using namespace calibration_detail;

// The residuals (and Jacobian) of every measurement at the last point Ceres asked for.
class Cache : public ceres::EvaluationCallback {
 public:
  Cache(Evaluator& e, const Eigen::VectorXd& scale, double* x) : e_(e), scale_(scale), x_(x) {}

  // Ceres has put the point into the parameter block.
  void PrepareForEvaluation(bool evaluate_jacobians, bool /*new_evaluation_point*/) override {
    ensure(x_, evaluate_jacobians);
  }

  // The residuals at z (and the Jacobian if asked). The measurements at a new point are solved
  // warm from the last iterate's answers (the first point cold, along the model's own loading
  // path), each to Newton's tolerance kPolishTolerance: there quadratic convergence makes the
  // answer independent of its start far below the options' tolerance, so the cost stays one
  // function of the parameters. (Warm answers at only that tolerance differ from cold ones within
  // it, and near the optimum that noise exceeded Levenberg-Marquardt's predicted decrease: PRB
  // with tip forces took 12 iterations instead of 5.) The differences start warm from these.
  void ensure(const double* z, bool jacobian) {
    const Eigen::Map<const Eigen::VectorXd> zv(z, scale_.size());
    if (have_ && zv != z_ && have_iterate_ && zv == iterate_.z) {
      current_ = iterate_;  // back at the iterate (a rejected step, the final report)
      z_ = zv;
      have_jacobian_ = true;
    }
    if (!have_ || zv != z_) {
      Point next;
      next.z = zv;
      next.values = next.z.cwiseProduct(scale_);
      const std::vector<Prediction>* warm = have_iterate_ ? &iterate_.predictions : have_ ? &current_.predictions : nullptr;
      next.predictions = e_.predict(next.values, warm, true);
      next.r = e_.residuals(next.predictions, next.values, &next.ok);
      current_ = std::move(next);
      z_ = zv;
      have_ = true;
      have_jacobian_ = false;
    }
    if (jacobian && !have_jacobian_) {
      e_.jacobian_at(current_.values, current_.predictions, current_.r, current_.ok, &current_.J);
      have_jacobian_ = true;
      iterate_ = current_;
      have_iterate_ = true;
    }
  }

  const Eigen::VectorXd& r() const { return current_.r; }
  const Eigen::MatrixXd& J() const { return current_.J; }
  bool ok(int i) const { return current_.ok[static_cast<std::size_t>(i)]; }
  const std::vector<Prediction>& predictions() const { return current_.predictions; }

 private:
  struct Point {
    Eigen::VectorXd z, values, r;
    Eigen::MatrixXd J;
    std::vector<bool> ok;
    std::vector<Prediction> predictions;
  };
  Evaluator& e_;
  Eigen::VectorXd scale_;
  double* x_;
  bool have_ = false, have_jacobian_ = false, have_iterate_ = false;
  Eigen::VectorXd z_;
  Point current_, iterate_;
};

// One measurement's residual block: its rows of the cache.
class SampleCost : public ceres::CostFunction {
 public:
  SampleCost(Cache& cache, const Evaluator& e, int i) : cache_(cache), i_(i), offset_(e.offset(i)) {
    set_num_residuals(e.size(i));
    mutable_parameter_block_sizes()->push_back(e.parameters());
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const bool want = jacobians && jacobians[0];
    cache_.ensure(parameters[0], want);
    if (!cache_.ok(i_)) return false;
    const int m = num_residuals(), n = parameter_block_sizes()[0];
    for (int k = 0; k < m; ++k) residuals[k] = cache_.r()[offset_ + k];
    if (want)
      for (int k = 0; k < m; ++k)
        for (int q = 0; q < n; ++q) jacobians[0][k * n + q] = cache_.J()(offset_ + k, q);
    return true;
  }

 private:
  Cache& cache_;
  int i_, offset_;
};

ceres::LossFunction* make_loss(const CalibrationOptions& o) {
  switch (o.loss) {
    case CalibrationLoss::Huber: return new ceres::HuberLoss(o.loss_scale);
    case CalibrationLoss::Cauchy: return new ceres::CauchyLoss(o.loss_scale);
    case CalibrationLoss::None: break;
  }
  return nullptr;
}

}  // namespace

std::string CalibrationSummary::brief_report() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s: %d iterations, %d solves, position RMS %.3g -> %.3g m (max %.3g -> %.3g m), %.3g s",
                converged ? "converged" : "not converged", iterations, forward_solves, before.rms_position,
                after.rms_position, before.max_position, after.max_position, time_s);
  return buf;
}

CalibrationResult calibrate(const Scene& scene, const CalibrationData& data, const CalibrationOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  options.validate();
  scene.validate();
  if (data.samples.empty()) throw InputError(data.source.empty() ? "data" : data.source, "", "no measurements");
  const std::string source = data.source.empty() ? std::string("data") : data.source;
  {
    const std::unique_ptr<StaticModel> probe = make_model(options.model, scene);
    for (const CalibrationSample& s : data.samples) {
      try {
        probe->check_input(s.input);
      } catch (const InputError& e) {
        throw InputError(source + " line " + std::to_string(s.line) + ": " + e.field(), e.value(), e.what());
      }
    }
  }
  std::vector<Parameter> params = resolve_parameters(scene, options.parameters);
  const int np = static_cast<int>(params.size());
  Eigen::VectorXd scale(np), z(np), initial(np);
  for (int q = 0; q < np; ++q) {
    scale[q] = params[static_cast<std::size_t>(q)].scale;
    initial[q] = params[static_cast<std::size_t>(q)].initial;
  }
  z = initial.cwiseQuotient(scale);

  Evaluator evaluator(scene, data, params, options);
  Cache cache(evaluator, scale, z.data());
  cache.ensure(z.data(), false);
  for (int i = 0; i < evaluator.samples(); ++i)
    if (!cache.ok(i))
      throw InputError(source + " line " +
                           std::to_string(data.samples[static_cast<std::size_t>(i)].line),
                       "", "the " + to_string(options.model) + " model does not converge for this measurement at the "
                           "starting parameters (check the row's inputs against the scene)");
  CalibrationResult out;
  out.residuals_before = evaluator.sample_residuals(cache.predictions(), initial);
  out.summary.before = statistics(out.residuals_before, cache.r());

  ceres::Problem::Options po;
  po.evaluation_callback = &cache;
  ceres::Problem problem(po);
  for (int i = 0; i < evaluator.samples(); ++i)
    problem.AddResidualBlock(new SampleCost(cache, evaluator, i), make_loss(options), z.data());
  for (int q = 0; q < np; ++q) {
    const Parameter& p = params[static_cast<std::size_t>(q)];
    if (std::isfinite(p.lower)) problem.SetParameterLowerBound(z.data(), q, p.lower / p.scale);
    if (std::isfinite(p.upper)) problem.SetParameterUpperBound(z.data(), q, p.upper / p.scale);
  }
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = options.function_tolerance;
  so.parameter_tolerance = options.parameter_tolerance;
  so.gradient_tolerance = options.gradient_tolerance;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);

  const Eigen::VectorXd values = z.cwiseProduct(scale);
  cache.ensure(z.data(), true);
  out.residuals_after = evaluator.sample_residuals(cache.predictions(), values);
  out.summary.after = statistics(out.residuals_after, cache.r());
  out.summary.converged = summary.termination_type == ceres::CONVERGENCE;
  out.summary.termination = ceres::TerminationTypeToString(summary.termination_type);
  out.summary.message = summary.message;
  out.summary.iterations = static_cast<int>(summary.iterations.size()) - 1;
  out.summary.initial_cost = summary.initial_cost;
  out.summary.final_cost = summary.final_cost;
  out.scene = apply_parameters(scene, params, values);
  out.scene.model = to_string(options.model);
  out.base = base_frame(params, values);
  fill_report(evaluator, values, cache.r(), cache.J(), data.has_std, options, out);
  out.summary.forward_solves = evaluator.forward_solves();
  out.summary.failed_solves = evaluator.failed_solves();
  out.summary.linearised_answers = evaluator.linearised();
  out.summary.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace tdcr
