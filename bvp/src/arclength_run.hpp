/// @file arclength_run.hpp
/// @brief Private to bvp: one call of arclength_continuation() and the state its steps share.
/// Its parts live in one file each: the path loop (arclength.cpp), event location and the final
/// solve at the target (arclength_events.cpp), snaps and their landings (arclength_landing.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Core>

#include "bordered_system.hpp"
#include "tdcr/bvp/arclength.hpp"

namespace tdcr::bvp::detail {

/// A point of the curve: y = (x, lambda), its unit scaled tangent t, the sign and log|.| of
/// the augmented determinant, and its scaled arclength s.
struct CurvePoint {
  Eigen::VectorXd y, t;
  int det_sign = 0;
  double det_log = 0.0;
  double s = 0.0;
  void resize(int n1) {
    y.resize(n1);
    t.resize(n1);
  }
};

/// A bracket [sa, sb] of a root of g for regula falsi with the Illinois modification (halve the
/// stale end's value when the same end moves twice), so convergence stays superlinear.
struct IllinoisBracket {
  double sa, sb, ga, gb;
  int side = 0;
  double next() const {
    const double s = (sa * gb - sb * ga) / (gb - ga);
    return s > sa && s < sb ? s : 0.5 * (sa + sb);
  }
  // Move the end whose g has the sign of g(sigma); true if that is the a end.
  bool update(double sigma, double g) {
    if ((g > 0.0) == (ga > 0.0)) {
      sa = sigma;
      ga = g;
      if (side == -1) gb *= 0.5;
      side = -1;
      return true;
    }
    sb = sigma;
    gb = g;
    if (side == +1) ga *= 0.5;
    side = +1;
    return false;
  }
};

/// One call of arclength_continuation(): the state shared by its steps.
class ArclengthRun {
 public:
  ArclengthRun(NewtonSolver& newton, ParameterizedSystem& system, const NewtonOptions& newton_options,
      const ArclengthOptions& options, ArclengthResult& result);

  /// Follows the path from x (in: a solution or a good guess at the start; out: the solution at
  /// the result's parameter) and fills the result.
  void run(Eigen::VectorXd& x);

 private:
  double lambda(const CurvePoint& p) const { return p.y[n_]; }
  bool before_target(double l) const { return dir_ * (l - opt_.target) < 0.0; }
  double scaled_distance(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
    return (a - b).cwiseProduct(w_).norm();
  }
  bool tangent(CurvePoint& p, const Eigen::VectorXd& border) {
    return bordered_.tangent(p.y, border, p.t, p.det_sign, p.det_log);
  }
  void reach(const CurvePoint& p) {
    push(p);
    sol_ = p.y;
    res_.status = ArclengthStatus::Reached;
  }
  void stall(const std::string& why) {
    res_.status = ArclengthStatus::Stalled;
    why_ = why;
  }

  // The path (arclength.cpp).
  void count(const NewtonResult& r, bool natural);
  bool natural_solve(double lambda, Eigen::VectorXd& x, const NewtonOptions* options = nullptr);
  bool correct(const CurvePoint& from, double sigma, const Eigen::VectorXd& guess, CurvePoint& out);
  int push(const CurvePoint& p);
  void record(ArclengthEventType type, const CurvePoint& p, bool refined, double jump = 0.0, int damped_steps = 0);

  // Events and the target (arclength_events.cpp).
  double test_value(ArclengthEventType type, const CurvePoint& p, double ref_log) const;
  bool refine(ArclengthEventType type, CurvePoint& event);
  bool finish(const CurvePoint& a, const CurvePoint& b, bool b_is_fold);
  bool step_events(bool& done);

  // Snaps (arclength_landing.cpp).
  bool snap(const CurvePoint& fold);
  bool land(const CurvePoint& fold, double landing, int damped_steps = 0);
  bool accepted_landing(double landing);
  int damped_landing(const CurvePoint& fold, double landing, const NewtonOptions& attempt);
  double undamped_norm(const Eigen::VectorXd& x);

  NewtonSolver& newton_;
  ParameterizedSystem& sys_;
  const NewtonOptions& nopt_;
  NewtonOptions corrector_ = nopt_;  // nopt_ with ArclengthOptions::corrector_max_iterations
  const ArclengthOptions& opt_;
  ArclengthResult& res_;
  const int n_;
  const double span_, dir_;
  BorderedSystem bordered_;
  const Eigen::VectorXd& w_;
  CurvePoint prev_, cur_, probe_, best_, fold_, bif_, a_, b_;
  Eigen::VectorXd y_pred_, guess_, xn_, phi_, sol_, f_, f_scale_, ref_;
  std::string why_;
  std::string rejected_;  // why the last snap landing was rejected (ArclengthOptions::accept_landing)
  bool start_ok = false;
};

}  // namespace tdcr::bvp::detail
