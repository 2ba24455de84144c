// Phase 2 of the inverse solve (inverse_solver.hpp): from a point on the target, a local minimum of
// |T| on it (the method is in inverse_solve.cpp's opening comment).
#include "services/inverse_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

namespace tdcr::detail::inverse {

// Gauss-Newton corrections over the free tendons from a trial point back onto the target (to
// kRestoreFraction of the tolerance, or as close as they get within it): on the Jacobian of
// the step's start (a chord method: the trial moved little), then, where a correction does not
// halve the error, on the Jacobian at the last corrected point; at most kCorrections forward
// solves. Then c's own Jacobian.
bool Solver::restore(Point& c, const MatrixXd& J0, const std::vector<int>& free) {
  MatrixXd J = J0;
  bool chord = true;
  const double goal = kRestoreFraction * error_tolerance();
  for (int k = 0; k < kCorrections && c.merit() > goal; ++k) {
    if (exhausted()) return false;
    ++r_.iterations;
    Point next;
    const VectorXd y = damped_step(J, c.e, c.T, lambda_floor(J), free);
    if (evaluate(y, &c, next, Mode::Precise) && next.merit() <= 0.5 * c.merit()) {
      c = std::move(next);
      continue;
    }
    if (c.reached) break;  // as close as the corrections get
    if (!chord || !jacobian(c)) return false;
    J = c.J;
    chord = false;
  }
  return c.reached && jacobian(c);
}

// The reduced Hessian B = I - Z^T K Z, K = sum_i lambda_i d2 e_i the Hessian of phi = lambda^T e,
// by second differences of phi along the tangent directions (central, or one-sided where a
// tension would turn negative; off the diagonal, along the sum of two directions), increment
// kHessianStep max(|T|, tension scale). hessian_complete_ false if an entry could not be formed.
MatrixXd Solver::reduced_hessian(const Point& cur, const Structure& s) {
  const Eigen::Index q = s.Z.cols(), f = s.Z.rows(), m = cur.T.size();
  MatrixXd B = MatrixXd::Identity(q, q);
  if (q == 0) return B;
  const double delta0 = kHessianStep * std::max(cur.T.norm(), tension_scale_);
  const double phi0 = s.lambda.dot(cur.e);
  std::vector<VectorXd> w(static_cast<std::size_t>(q), VectorXd::Zero(m));
  for (Eigen::Index j = 0; j < q; ++j)
    for (Eigen::Index c = 0; c < f; ++c) w[static_cast<std::size_t>(j)][s.free[static_cast<std::size_t>(c)]] = s.Z(c, j);
  // Largest t with T + t v >= 0.
  auto room = [&](const VectorXd& v) {
    double t = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < m; ++i)
      if (v[i] < 0.0) t = std::min(t, cur.T[i] / -v[i]);
    return t;
  };
  auto phi = [&](const VectorXd& T_, double& value) {
    const VectorXd T = T_.cwiseMax(0.0);  // rounding at a bound
    Point p;
    if (!evaluate(T, &cur, p, Mode::Difference)) return false;
    value = s.lambda.dot(p.e);
    return true;
  };
  // Diagonal: phi at +-delta w_j (or at delta w_j and 2 delta w_j along the feasible sign).
  std::vector<double> step(static_cast<std::size_t>(q), 0.0), phi1(static_cast<std::size_t>(q), 0.0);
  for (Eigen::Index j = 0; j < q; ++j) {
    const VectorXd& v = w[static_cast<std::size_t>(j)];
    const double up = room(v), down = room(-v);
    double delta = std::min(delta0, std::min(up, down)), sign = 1.0, a = 0.0, b = 0.0;
    bool central = delta >= 1e-3 * delta0;
    if (!central) {
      sign = up >= down ? 1.0 : -1.0;
      delta = std::min(delta0, 0.5 * std::max(up, down));
    }
    if (delta < 1e-3 * delta0 || !phi(cur.T + sign * delta * v, a) ||
        !phi(cur.T + (central ? -delta : 2.0 * sign * delta) * v, b)) {
      hessian_complete_ = false;
      continue;
    }
    B(j, j) -= (central ? a + b - 2.0 * phi0 : b - 2.0 * a + phi0) / (delta * delta);
    step[static_cast<std::size_t>(j)] = sign * delta;
    phi1[static_cast<std::size_t>(j)] = a;
  }
  // Off the diagonal: (phi(d_j w_j + d_k w_k) - phi(d_j w_j) - phi(d_k w_k) + phi0) / (d_j d_k).
  for (Eigen::Index j = 0; j < q; ++j)
    for (Eigen::Index k = j + 1; k < q; ++k) {
      const double dj = step[static_cast<std::size_t>(j)], dk = step[static_cast<std::size_t>(k)];
      const VectorXd v = dj * w[static_cast<std::size_t>(j)] + dk * w[static_cast<std::size_t>(k)];
      double c = 0.0;
      if (dj == 0.0 || dk == 0.0 || room(v) < 1.0 || !phi(cur.T + v, c)) {
        hessian_complete_ = false;
        continue;
      }
      B(j, k) = B(k, j) = -(c - phi1[static_cast<std::size_t>(j)] - phi1[static_cast<std::size_t>(k)] + phi0) / (dj * dk);
    }
  return B;
}

// Local minimum of |T| on the target from the feasible point `cur`. Ends with cur on the
// target and minimum_norm, optimality, tension_resolution and message_ set.
void Solver::minimise_norm(Point& cur) {
  const Eigen::Index m = cur.T.size();
  std::vector<bool> released(static_cast<std::size_t>(m), false), blocked(static_cast<std::size_t>(m), false);
  r_.minimum_norm = false;
  message_.clear();
  int unseen = 0;        // steps in a row kept below the Lagrangian's noise
  double reach = 1.0;    // the first step length tried: 4 times the last one kept (at most 1)
  while (true) {
    std::vector<int> free;
    for (Eigen::Index i = 0; i < m; ++i)
      if (cur.T[i] > 0.0 || released[static_cast<std::size_t>(i)]) free.push_back(static_cast<int>(i));
    const Structure s = structure(cur.J, cur.T, free);
    const Eigen::Index q = s.Z.cols();
    hessian_complete_ = true;
    const MatrixXd B = reduced_hessian(cur, s);
    // The Newton step u = -B^-1 g with |eigenvalues| (a direction of descent where B is not
    // positive definite); along the most negative curvature where that step vanishes.
    VectorXd u = VectorXd::Zero(q);
    bool positive = hessian_complete_;
    if (q > 0) {
      const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(B);
      const VectorXd& ev = eig.eigenvalues();
      positive = positive && ev[0] > kCurvatureFloor;
      const VectorXd gq = eig.eigenvectors().transpose() * s.g;
      VectorXd uq(q);
      for (Eigen::Index i = 0; i < q; ++i) uq[i] = -gq[i] / std::max(std::abs(ev[i]), kCurvatureFloor);
      u = eig.eigenvectors() * uq;
      if (ev[0] < -kCurvatureFloor && (s.Z * u).cwiseAbs().maxCoeff() <= options_.tension_tolerance) {
        const double t = 0.1 * std::max(cur.T.norm(), tension_scale_);
        u = (gq[0] > 0.0 ? -t : t) * eig.eigenvectors().col(0);
      }
    }
    VectorXd d = VectorXd::Zero(m);
    const VectorXd Zu = s.Z * u;
    for (std::size_t c = 0; c < free.size(); ++c) d[free[c]] = Zu[static_cast<Eigen::Index>(c)];
    const double step = d.cwiseAbs().maxCoeff();
    // Below the tensions' resolution on the target (the tension change that moves the tip by
    // the tolerance in its least controllable direction) a step cannot be told from the
    // target's own tolerance, nor from the error the Jacobian's gives the tangent basis.
    r_.tension_resolution = s.sigma_min > 0.0 ? error_tolerance() / s.sigma_min : 0.0;
    r_.optimality = step;
    // The end: frees the slack tendon whose multiplier is most negative (pulling it lowers |T|),
    // if any (false: go on), else checks the conditions of a local minimum at `threshold`.
    auto conclude = [&](double threshold) {
      int release = -1;
      for (Eigen::Index i = 0; i < m; ++i)
        if (cur.T[i] == 0.0 && !released[static_cast<std::size_t>(i)] && !blocked[static_cast<std::size_t>(i)] &&
            s.mu[i] < -threshold && (release < 0 || s.mu[i] < s.mu[release]))
          release = static_cast<int>(i);
      if (release >= 0) {
        released[static_cast<std::size_t>(release)] = true;
        return false;
      }
      bool kkt = true;
      for (Eigen::Index i = 0; i < m; ++i)
        if (cur.T[i] == 0.0 && !released[static_cast<std::size_t>(i)] && s.mu[i] < -threshold) kkt = false;
      r_.minimum_norm = kkt && positive;
      if (!kkt)
        message_ = "a slack tendon's multiplier is negative, but pulling it leaves the target: minimum norm not verified";
      else if (!positive)
        message_ = "a stationary point of |T| on the target whose reduced Hessian is not positive definite (or could "
                   "not be formed): minimum norm not verified";
      else if (step > options_.tension_tolerance)
        message_ = "the last Newton step is below the tensions' resolution on the target, not below tension_tolerance";
      return true;
    };
    if (step <= options_.tension_tolerance) {
      if (conclude(options_.tension_tolerance)) return;
      continue;
    }
    if (exhausted()) {
      message_ = "iteration limit before the minimum norm was verified";
      return;
    }
    // Longest step that keeps T >= 0; the tendon that blocks it is fixed at zero.
    double alpha_max = 1.0;
    int blocking = -1;
    for (Eigen::Index i = 0; i < m; ++i)
      if (d[i] < 0.0 && cur.T[i] + alpha_max * d[i] < 0.0) {
        alpha_max = cur.T[i] / -d[i];
        blocking = static_cast<int>(i);
      }
    if (alpha_max <= 0.0) {  // a freed tendon would have to push: it stays fixed
      for (int i : free)
        if (cur.T[i] == 0.0 && d[i] < 0.0) {
          released[static_cast<std::size_t>(i)] = false;
          blocked[static_cast<std::size_t>(i)] = true;
        }
      continue;
    }
    // Line search on the Lagrangian with this step's multipliers, each trial brought back onto
    // the target first. Below `noise` (the Lagrangian's scatter between points on the target,
    // about 1e-12 |T|^2) a decrease cannot be seen: a full step the quadratic model predicts to
    // gain less is kept once back on the target, at most kUnseenSteps times in a row.
    const double L0 = 0.5 * cur.T.squaredNorm() - s.lambda.dot(cur.e);
    const double slope = std::min(s.g.dot(u), 0.0);  // d L / d alpha at 0
    const double noise = 1e-11 * (cur.T.squaredNorm() + tension_scale_ * tension_scale_);
    const double predicted = -slope - 0.5 * u.dot(B * u);
    bool kept = false;
    const double alpha0 = std::min(alpha_max, reach);
    for (double alpha = alpha0; !kept && alpha >= alpha0 / 256.0; alpha /= 4.0) {
      if (exhausted()) break;
      VectorXd T = (cur.T + alpha * d).cwiseMax(0.0);
      std::vector<int> trial_free = free;
      if (alpha == alpha_max && blocking >= 0) {
        T[blocking] = 0.0;
        trial_free.erase(std::remove(trial_free.begin(), trial_free.end(), blocking), trial_free.end());
      }
      ++r_.iterations;
      Point c;
      if (!evaluate(T, &cur, c, Mode::Precise) || !restore(c, cur.J, trial_free)) continue;
      const double L = 0.5 * c.T.squaredNorm() - s.lambda.dot(c.e);
      const bool unseen_step = alpha == alpha_max && predicted <= noise;
      if (L > L0 + 1e-4 * alpha * slope + noise && !unseen_step) continue;
      if (unseen_step && ++unseen > kUnseenSteps) break;
      if (!unseen_step) unseen = 0;
      kept = true;
      reach = std::min(1.0, 4.0 * alpha);
      cur = std::move(c);
      ++r_.accepted_steps;
      std::fill(released.begin(), released.end(), false);
      std::fill(blocked.begin(), blocked.end(), false);
    }
    if (!kept && !exhausted() && step <= r_.tension_resolution) {  // no gain the merit can see
      if (conclude(r_.tension_resolution)) return;
      continue;
    }
    if (!kept) {
      message_ = exhausted()
                     ? "iteration limit before the minimum norm was verified"
                     : "no step along the target lowers |T| any more, but the optimality conditions do not hold: "
                       "minimum norm not verified";
      return;
    }
  }
}

}  // namespace tdcr::detail::inverse
