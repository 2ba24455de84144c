// The calibration's evaluator: every measurement solved by one model per parameter vector (warm
// from the last iterate's answers, polished); standardised residuals; the Jacobian by forward
// differences with one model rebuild per model parameter, each measurement's shifted answer by
// the implicit function theorem (AnswerLinearisation) or solved warm from its answer at the
// unshifted parameters (tdcr::warm_start_from_other_robot); the base frame's by differences of
// the transform.
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "calibration_detail.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr::calibration_detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The frame at arc length s from the disk frames: a disk's own frame, or between two disks the
// screw motion between them (exact on a constant-curvature-and-twist arc).
Frame frame_at(const std::vector<Frame>& frames, const std::vector<double>& disk_s, double s) {
  const std::size_t n = disk_s.size();
  if (s >= disk_s.back()) return frames.back();
  const std::size_t j = static_cast<std::size_t>(std::upper_bound(disk_s.begin(), disk_s.end(), s) - disk_s.begin());
  const std::size_t i = j == 0 ? 0 : std::min(j - 1, n - 2);
  const double h = disk_s[i + 1] - disk_s[i];
  const double t = std::clamp((s - disk_s[i]) / h, 0.0, 1.0);
  if (t == 0.0) return frames[i];
  const Frame& A = frames[i];
  const Frame& B = frames[i + 1];
  const Vec3 w = lie::log_so3(A.R.transpose() * B.R);
  const Vec3 v = lie::left_jacobian_so3(w).inverse() * (A.R.transpose() * (B.p - A.p));
  return A * lie::exp_se3(t * w, t * v);
}

}  // namespace

Evaluator::Evaluator(const Scene& scene, const CalibrationData& data, std::vector<Parameter> params,
                     const CalibrationOptions& options)
    : scene_(scene), data_(data), params_(std::move(params)), options_(options) {
  solver_ = scene.solver;
  solver_.function_tolerance = options.solve_function_tolerance;
  solver_.stability = StabilityCheck::Never;
  solver_.differential_kinematics = false;
  // Exact Newton from a fresh Jacobian in every solve: an answer that depends on the workspace's
  // last solve (within the tolerance) would put that history into the differences.
  solver_.reuse_jacobian = false;
  solver_.extrapolate_warm_starts = false;
  // A mesh that does not move with the parameters (the differences see the model, not a remesh):
  // the finest mesh the accuracy-driven integrator chooses for the measurements at the start.
  if (solver_.integrator == IntegratorKind::AccuracyDrivenRK4 &&
      (options.model == ModelKind::VC || options.model == ModelKind::VCref)) {
    int halvings = 0;
    const auto model = make_model(options.model, scene);
    const auto ws = model->make_workspace();
    SolverOptions probe = solver_;
    probe.function_tolerance = scene.solver.function_tolerance;
    for (const CalibrationSample& m : data.samples) {
      const Solution s = solve(*model, *ws, m.input, probe);
      ++solves_;
      if (s.converged()) halvings = std::max(halvings, s.summary.rk4_halvings);
    }
    solver_.integrator = IntegratorKind::FixedStepRK4;
    solver_.rk4_steps = SolverOptions::kFirstMeshRk4Steps << halvings;
    solver_.rk4_max_step = SolverOptions::kFirstMeshRk4MaxStep / static_cast<double>(1 << halvings);
  } else if (solver_.integrator == IntegratorKind::AccuracyDrivenRK4) {
    solver_.integrator = IntegratorKind::FixedStepRK4;
  }
  // The residual points' solves: Newton to near the rounding floor of the residual, where its
  // quadratic convergence leaves the answer independent of the start (warm from the last
  // iterate, or cold) to far below the tolerance the differences need.
  polish_ = solver_;
  polish_.function_tolerance = std::min(options.solve_function_tolerance, kPolishTolerance);
  offsets_.push_back(0);
  for (const CalibrationSample& s : data.samples)
    offsets_.push_back(offsets_.back() + (s.tip ? 3 : 0) + (s.rotation ? 3 : 0) + 3 * static_cast<int>(s.points.size()));
}

std::vector<Prediction> Evaluator::predict(const Eigen::VectorXd& values, const std::vector<Prediction>* warm,
                                          bool polish, const std::vector<AnswerLinearisation>* linear) {
  std::vector<Prediction> out(data_.samples.size());
  const Scene scene = apply_parameters(scene_, params_, values);
  std::unique_ptr<StaticModel> model;
  try {
    scene.robot.validate();
    model = make_model(options_.model, scene);
  } catch (const InputError&) {
    return out;  // e.g. a tendon moved onto the axis: nothing solves here
  }
  auto ws = model->make_workspace();
  const std::vector<double>& disk_s = model->routing().disk_s;
  for (int i = 0; i < samples(); ++i) {
    const auto u = static_cast<std::size_t>(i);
    const CalibrationSample& m = data_.samples[u];
    const bool from = options_.warm_start && warm && (*warm)[u].solved;
    Solution s;
    if (linear && (*linear)[u].valid() && (*linear)[u].predict(*model, *ws, m.input, solver_, s)) {
      ++linearised_;
    } else if (from) {
      const Solution start = warm_start_from_other_robot(*model, (*warm)[u].solution);
      s = solve(*model, *ws, m.input, polish ? polish_ : solver_, &start);
      ++solves_;
    }
    if (!s.converged()) {
      s = solve(*model, *ws, m.input, solver_);
      ++solves_;
      if (polish && options_.warm_start && s.converged()) {
        // A cold answer polished like the warm ones, so that all residual points agree.
        Solution t = solve(*model, *ws, m.input, polish_, &s);
        ++solves_;
        if (t.converged()) s = std::move(t);
      }
    }
    Prediction& p = out[u];
    p.solved = s.converged() && !s.disk_frames.empty();
    if (!p.solved) {
      ++failed_;
      continue;
    }
    p.frames.push_back(s.tip());
    for (const MeasuredPoint& q : m.points) p.frames.push_back(frame_at(s.disk_frames, disk_s, q.s));
    p.solution = std::move(s);
  }
  return out;
}

Eigen::VectorXd Evaluator::residuals(const std::vector<Prediction>& p, const Eigen::VectorXd& values,
                                     std::vector<bool>* ok) const {
  const Frame base = base_frame(params_, values);
  Eigen::VectorXd r = Eigen::VectorXd::Zero(residual_count());
  if (ok) ok->assign(data_.samples.size(), true);
  auto std_of = [](double given, double fallback) { return std::isfinite(given) ? given : fallback; };
  for (int i = 0; i < samples(); ++i) {
    const CalibrationSample& m = data_.samples[static_cast<std::size_t>(i)];
    const Prediction& q = p[static_cast<std::size_t>(i)];
    if (!q.solved) {
      if (ok) (*ok)[static_cast<std::size_t>(i)] = false;
      continue;
    }
    int o = offset(i);
    const Frame tip = base * q.frames[0];
    if (m.tip) {
      for (int k = 0; k < 3; ++k) r[o + k] = (tip.p[k] - (*m.tip)[k]) / std_of(m.tip_std[k], options_.position_std);
      o += 3;
    }
    if (m.rotation) {
      const Vec3 e = lie::log_so3(tip.R * lie::exp_so3(*m.rotation).transpose());
      for (int k = 0; k < 3; ++k) r[o + k] = e[k] / std_of(m.rotation_std[k], options_.rotation_std);
      o += 3;
    }
    for (std::size_t j = 0; j < m.points.size(); ++j) {
      const Vec3 x = base.R * q.frames[j + 1].p + base.p;
      for (int k = 0; k < 3; ++k)
        r[o + k] = (x[k] - m.points[j].position[k]) / std_of(m.points[j].std[k], options_.position_std);
      o += 3;
    }
  }
  return r;
}

void Evaluator::jacobian_at(const Eigen::VectorXd& values, const std::vector<Prediction>& p, const Eigen::VectorXd& r,
                            std::vector<bool>& ok, Eigen::MatrixXd* jacobian) {
  const int np = parameters();
  jacobian->setZero(residual_count(), np);
  // The implicit function theorem: every answer linearised once at `values` (F_x), then each
  // model parameter's column from one residual evaluation and one output pass per measurement.
  std::vector<AnswerLinearisation> linear;
  bool any_model_parameter = false;
  for (const Parameter& par : params_) any_model_parameter = any_model_parameter || !is_base_parameter(par.kind);
  if (options_.jacobian == CalibrationJacobian::ImplicitFunction && any_model_parameter) {
    linear.resize(data_.samples.size());
    try {
      const Scene scene = apply_parameters(scene_, params_, values);
      const auto model = make_model(options_.model, scene);
      const auto ws = model->make_workspace();
      for (int i = 0; i < samples(); ++i) {
        const auto u = static_cast<std::size_t>(i);
        if (p[u].solved) linear[u].linearise(*model, *ws, data_.samples[u].input, solver_, p[u].solution);
      }
    } catch (const InputError&) {
      linear.clear();  // the differences then solve (and say why a measurement fails)
    }
  }
  for (int q = 0; q < np; ++q) {
    const Parameter& par = params_[static_cast<std::size_t>(q)];
    const double h = options_.difference_step * par.scale;
    if (is_base_parameter(par.kind)) {
      // The transform alone: central differences, no solve.
      Eigen::VectorXd plus = values, minus = values;
      plus[q] += h;
      minus[q] -= h;
      jacobian->col(q) = (residuals(p, plus, nullptr) - residuals(p, minus, nullptr)) * (par.scale / (2.0 * h));
      continue;
    }
    // Forward difference, backward at an upper bound; a measurement that fails one way is
    // differenced the other way.
    const double dir = values[q] + h > par.upper ? -1.0 : 1.0;
    Eigen::VectorXd shifted = values;
    shifted[q] += dir * h;
    std::vector<bool> ok1;
    const Eigen::VectorXd r1 = residuals(predict(shifted, &p, false, linear.empty() ? nullptr : &linear), shifted, &ok1);
    std::vector<bool> ok2;
    Eigen::VectorXd r2;
    bool other_way = false;
    for (int i = 0; i < samples(); ++i) other_way = other_way || (ok[static_cast<std::size_t>(i)] && !ok1[static_cast<std::size_t>(i)]);
    if (other_way) {
      Eigen::VectorXd back = values;
      back[q] -= dir * h;
      r2 = residuals(predict(back, &p), back, &ok2);
    }
    for (int i = 0; i < samples(); ++i) {
      const auto u = static_cast<std::size_t>(i);
      if (!ok[u]) continue;
      if (ok1[u])
        jacobian->col(q).segment(offset(i), size(i)) = (r1.segment(offset(i), size(i)) - r.segment(offset(i), size(i))) * (dir * par.scale / h);
      else if (other_way && ok2[u])
        jacobian->col(q).segment(offset(i), size(i)) = (r.segment(offset(i), size(i)) - r2.segment(offset(i), size(i))) * (dir * par.scale / h);
      else
        ok[u] = false;
    }
  }
}

std::vector<SampleResidual> Evaluator::sample_residuals(const std::vector<Prediction>& p, const Eigen::VectorXd& values) const {
  const Frame base = base_frame(params_, values);
  std::vector<bool> ok;
  const Eigen::VectorXd r = residuals(p, values, &ok);
  std::vector<SampleResidual> out(data_.samples.size());
  for (int i = 0; i < samples(); ++i) {
    const CalibrationSample& m = data_.samples[static_cast<std::size_t>(i)];
    SampleResidual& s = out[static_cast<std::size_t>(i)];
    s.line = m.line;
    s.solved = ok[static_cast<std::size_t>(i)];
    if (!s.solved) {
      s.tip_error = s.rotation_error = s.point_error = s.standardised = kNaN;
      continue;
    }
    const Prediction& q = p[static_cast<std::size_t>(i)];
    const Frame tip = base * q.frames[0];
    if (m.tip) s.tip_error = (tip.p - *m.tip).norm();
    if (m.rotation) s.rotation_error = lie::rotation_angle(tip.R, lie::exp_so3(*m.rotation));
    for (std::size_t j = 0; j < m.points.size(); ++j)
      s.point_error = std::max(s.point_error, (base.R * q.frames[j + 1].p + base.p - m.points[j].position).norm());
    s.standardised = r.segment(offset(i), size(i)).norm();
  }
  return out;
}

ResidualStatistics statistics(const std::vector<SampleResidual>& r, const Eigen::VectorXd& standardised) {
  ResidualStatistics st;
  double sp = 0.0, sr = 0.0;
  int np = 0, nr = 0;
  for (const SampleResidual& s : r) {
    if (!s.solved) continue;
    sp += s.tip_error * s.tip_error + s.point_error * s.point_error;
    np += 1;
    st.max_position = std::max({st.max_position, s.tip_error, s.point_error});
    sr += s.rotation_error * s.rotation_error;
    nr += s.rotation_error > 0.0;
    st.max_rotation = std::max(st.max_rotation, s.rotation_error);
  }
  st.rms_position = np ? std::sqrt(sp / np) : kNaN;
  st.rms_rotation = nr ? std::sqrt(sr / nr) : 0.0;
  st.rms_standardised = standardised.size() ? std::sqrt(standardised.squaredNorm() / static_cast<double>(standardised.size())) : 0.0;
  return st;
}

}  // namespace tdcr::calibration_detail
