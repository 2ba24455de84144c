// The inverse solve's forward solves (inverse_solver.hpp): one forward solve at given tensions, the
// target error it gives, and the error's Jacobian by differences of forward solves.
#include "services/inverse_solver.hpp"

#include <algorithm>

#include <Eigen/LU>

#include "tdcr/core/lie.hpp"

namespace tdcr::detail::inverse {

namespace {

// Pose difference a - b: position difference and the rotation vector of R_a R_b^T (base frame).
Eigen::Matrix<double, 6, 1> pose_difference(const Frame& a, const Frame& b) {
  Eigen::Matrix<double, 6, 1> d;
  d << a.p - b.p, lie::log_so3(a.R * b.R.transpose());
  return d;
}

}  // namespace

// Forward solve at T, warm-started from `from`; cold (from the straight robot, along the
// loading path) if `from` is null or T loads a part of the robot that no tendon loads at
// `from` (a slack tendon pulled whose segment and all distal ones have only slack tendons):
// a warm start from a PRB subsegment that is exactly straight can converge to a spurious
// equilibrium whose bending plane is arbitrary. False if the solve failed.
// Mode::Step at kInnerFunctionTolerance; Mode::Precise at kDifferenceFunctionTolerance (where
// that converges, else as Step): a modified Newton iteration stopped at 1e-12 leaves a tip error
// that grows with the step, which the Lagrangian's multipliers (up to 1e4 N/m where a target
// coordinate is barely controllable) turn into a spurious slope; Mode::Difference as Precise,
// and warm from `from` whatever it loads (the differences check their consistency instead).
// `options`: these, cold.
bool Solver::evaluate(const VectorXd& T, const Point* from, Point& out, Mode mode, const SolverOptions* options) {
  const bool warm = !options && from != nullptr && (mode == Mode::Difference || !loads_unloaded_part(from->T, T));
  input_.actuation.values.assign(T.data(), T.data() + T.size());
  for (int attempt = mode == Mode::Step || options ? 1 : 0; attempt < 2; ++attempt) {
    out = Point();
    out.T = T;
    const bool tight = attempt == 0;
    const SolverOptions& o = options ? *options : warm ? (tight ? tight_ : warm_) : (tight ? tight_cold_ : cold_);
    out.solution = tdcr::solve(model_, ws_, input_, o, warm ? &from->solution : nullptr);
    ++r_.forward_solves;
    if (!out.solution.disk_frames.empty() && out.solution.converged()) {
      error(out);
      return true;
    }
  }
  return false;
}

bool Solver::loads_unloaded_part(const VectorXd& from, const VectorXd& to) const {
  const std::vector<RoutedTendon>& tendons = model_.routing().tendons;
  for (std::size_t i = 0; i < tendons.size(); ++i) {
    if (!(from[static_cast<Eigen::Index>(i)] == 0.0 && to[static_cast<Eigen::Index>(i)] > 0.0)) continue;
    bool unloaded = true;
    for (std::size_t k = 0; k < tendons.size() && unloaded; ++k)
      if (tendons[k].segment >= tendons[i].segment && from[static_cast<Eigen::Index>(k)] != 0.0) unloaded = false;
    if (unloaded) return true;
  }
  return false;
}

// The tolerance of the weighted error e: the position tolerance, and the rotation tolerance
// times the rotation weight if that is smaller.
double Solver::error_tolerance() const {
  return target_.rotation ? std::min(options_.position_tolerance, rotation_weight_ * options_.rotation_tolerance)
                          : options_.position_tolerance;
}

void Solver::error(Point& p) const {
  const Solution& s = p.solution;
  const Vec3 dp = s.tip().p - target_.position;
  p.position_error = dp.norm();
  p.rotation_error = 0.0;
  if (!target_.rotation) {
    p.e = dp;
  } else {
    const Vec3 er = lie::log_so3(s.tip().R * R_target_.transpose());
    p.rotation_error = er.norm();
    p.e.resize(6);
    p.e << dp, rotation_weight_ * er;
  }
  p.reached = p.position_error <= options_.position_tolerance &&
              (!target_.rotation || p.rotation_error <= options_.rotation_tolerance);
}

// d e / d T at p by differences of forward solves: central, or one-sided of second order
// ((4 g(h) - g(2h) - 3 g(0)) / 2h) where T_j < 2h (tensions cannot be negative), increment
// kDifferenceStep max(T_j, tension scale), warm-started from p with its tolerance at
// kDifferenceFunctionTolerance. A column whose three values are not consistent with a smooth
// map (second difference above a tenth of the first) is solved again cold: a warm start from a
// straight PRB subsegment can land on a spurious equilibrium. Rotation rows: e_r = w log(R
// R_t^T), d e_r = w J_l(e_r)^-1 dw for R -> exp([dw]) R.
bool Solver::jacobian(Point& p) {
  const Eigen::Index m = p.T.size();
  Eigen::Matrix<double, 6, Eigen::Dynamic> D(6, m);
  const Frame tip = p.solution.tip();
  Point a, b;
  for (Eigen::Index j = 0; j < m; ++j) {
    const double h = kDifferenceStep * std::max(p.T[j], tension_scale_);
    const bool central = p.T[j] >= 2.0 * h;
    VectorXd Ta = p.T, Tb = p.T;
    Ta[j] += h;
    Tb[j] += central ? -h : 2.0 * h;
    Eigen::Matrix<double, 6, 1> da, db;
    bool consistent = false;
    for (int attempt = 0; attempt < 2 && !consistent; ++attempt) {
      // Warm (the Newton Jacobian reused), then cold if the column is not consistent; each at
      // the tight tolerance where that converges, else at the inner one.
      const Point* from = attempt == 0 ? &p : nullptr;
      if (!evaluate(Ta, from, a, Mode::Difference) || !evaluate(Tb, from, b, Mode::Difference))
        return false;
      da = pose_difference(a.solution.tip(), tip);
      db = pose_difference(b.solution.tip(), tip);
      // central: da + db = h^2 g''; one-sided: db - 2 da = h^2 g''; both against h g'.
      const double second = central ? (da + db).norm() : (db - 2.0 * da).norm();
      const double first = central ? 0.5 * (da - db).norm() : da.norm();
      consistent = second <= 0.1 * first + kTipNoise;
    }
    if (central)
      D.col(j) = (da - db) / (2.0 * h);
    else
      D.col(j) = (4.0 * da - db) / (2.0 * h);
  }
  if (!D.allFinite()) return false;
  if (!target_.rotation) {
    p.J = D.topRows(3);
  } else {
    const Vec3 er = p.e.tail(3) / rotation_weight_;
    p.J.resize(6, m);
    p.J.topRows(3) = D.topRows(3);
    p.J.bottomRows(3) = rotation_weight_ * lie::left_jacobian_so3(er).lu().solve(D.bottomRows(3));
  }
  return true;
}

}  // namespace tdcr::detail::inverse
