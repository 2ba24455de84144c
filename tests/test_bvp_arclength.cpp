// bvp::arclength_continuation: pseudo-arclength continuation through folds, fold and
// bifurcation detection, snaps, the final solve at the target, failures and option checks.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "bvp_test_systems.hpp"
#include "solve/bvp_options.hpp"
#include "tdcr/bvp/arclength.hpp"
#include "tdcr/core/error.hpp"

using tdcr::bvp::ArclengthEventType;
using tdcr::bvp::ArclengthOptions;
using tdcr::bvp::ArclengthResult;
using tdcr::bvp::ArclengthStatus;
using tdcr::bvp::FoldAction;
using tdcr::bvp::NewtonOptions;
using tdcr::bvp::NewtonSolver;

namespace {

using Vec = Eigen::VectorXd;
using Residual = std::function<bool(const Vec& x, double lambda, Vec& f)>;
using Jacobian = std::function<void(const Vec& x, double lambda, Eigen::MatrixXd& J)>;

// F(x; lambda) given by functions; an analytic dense Jacobian if `jac` is set, a declared
// (dense) sparsity pattern with analytic sparse values if `sparse` is also set.
class FnSystem : public tdcr::bvp::ParameterizedSystem {
 public:
  FnSystem(int n, Residual f, Jacobian jac = nullptr, bool sparse = false)
      : n_(n), f_(std::move(f)), jac_(std::move(jac)), sparse_(sparse),
        pattern_(tdcr::bvp::SparsityPattern::dense(n)), x_(n), fx_(n), J_(n, n) {}
  int size() const override { return n_; }
  void set_parameter(double lambda) override { lambda_ = lambda; }
  bool residual(const Eigen::Ref<const Vec>& x, Eigen::Ref<Vec> f) override {
    ++evaluations;
    x_ = x;
    if (!f_(x_, lambda_, fx_)) return false;
    f = fx_;
    return true;
  }
  const tdcr::bvp::SparsityPattern* sparsity() const override { return sparse_ ? &pattern_ : nullptr; }
  bool has_jacobian() const override { return static_cast<bool>(jac_); }
  bool jacobian(const Eigen::Ref<const Vec>& x, const Eigen::Ref<const Vec>&,
                Eigen::Ref<Eigen::MatrixXd> J) override {
    x_ = x;
    jac_(x_, lambda_, J_);
    J = J_;
    return true;
  }
  bool sparse_jacobian(const Eigen::Ref<const Vec>& x, const Eigen::Ref<const Vec>&, double* v) override {
    x_ = x;
    jac_(x_, lambda_, J_);
    for (int j = 0; j < n_; ++j)
      for (int k = pattern_.col_ptr[j]; k < pattern_.col_ptr[j + 1]; ++k) v[k] = J_(pattern_.row_idx[k], j);
    return true;
  }
  void accept_step(Vec&) override { ++accepted; }
  void unknown_scale(Eigen::Ref<Vec> s) const override {
    if (uscale.size() == n_) s = uscale; else s.setOnes();
  }
  int evaluations = 0;
  int accepted = 0;
  Vec uscale;  // unknown_scale() if set, else ones

 private:
  int n_;
  Residual f_;
  Jacobian jac_;
  bool sparse_;
  tdcr::bvp::SparsityPattern pattern_;
  double lambda_ = 0.0;
  Vec x_, fx_;
  Eigen::MatrixXd J_;
};

const double kFold = 2.0 / (3.0 * std::sqrt(3.0));  // folds of x^3 - x at lambda = +-kFold
const double kPlastic = 1.324717957244746;            // the real root of x^3 - x - 1

// The S-curve x^3 - x = lambda.
FnSystem s_curve() {
  return FnSystem(1, [](const Vec& x, double l, Vec& f) {
    f[0] = x[0] * x[0] * x[0] - x[0] - l;
    return true;
  });
}

// From x = -1.2 on the lower branch to lambda = 1; the path records x.
ArclengthOptions s_curve_path(FoldAction at_fold) {
  ArclengthOptions o;
  o.start = -1.2 * 1.2 * 1.2 + 1.2;
  o.target = 1.0;
  o.at_fold = at_fold;
  o.output = [](const Vec& v, double) { return v[0]; };
  return o;
}

ArclengthResult follow(tdcr::bvp::ParameterizedSystem& s, Vec& x, const ArclengthOptions& o,
                       const NewtonOptions& n = NewtonOptions()) {
  NewtonSolver newton;
  return tdcr::bvp::arclength_continuation(newton, s, x, n, o);
}

}  // namespace

// The S-curve from the lower branch (x = -1.2) to lambda = 1: the path walks around both folds
// (up the lower branch, down the middle one, up the upper one) and ends on the only solution at
// lambda = 1. Both folds are located to 1e-6 in lambda, none is taken for a bifurcation, and
// every path point is a solution.
TEST(BvpArclength, SCurveFollowsBothFolds) {
  FnSystem s = s_curve();
  Vec x = Vec::Constant(1, -1.2);
  const ArclengthOptions o = s_curve_path(FoldAction::Continue);
  const ArclengthResult r = follow(s, x, o);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(r.status, ArclengthStatus::Reached);
  EXPECT_NEAR(x[0], kPlastic, 1e-10);
  EXPECT_DOUBLE_EQ(r.parameter, 1.0);
  EXPECT_EQ(s.accepted, 1);  // accept_step once, on the returned x
  ASSERT_EQ(r.count(ArclengthEventType::Fold), 2) << r.message;
  EXPECT_EQ(r.count(ArclengthEventType::Bifurcation), 0);
  EXPECT_EQ(r.count(ArclengthEventType::Snap), 0);
  EXPECT_NEAR(r.events[0].lambda, kFold, 1e-6);
  EXPECT_NEAR(r.events[0].x[0], -1.0 / std::sqrt(3.0), 1e-4);
  EXPECT_NEAR(r.events[1].lambda, -kFold, 1e-6);
  EXPECT_NEAR(r.events[1].x[0], 1.0 / std::sqrt(3.0), 1e-4);
  EXPECT_TRUE(r.events[0].refined && r.events[1].refined);
  EXPECT_LT(r.events[0].index, r.events[1].index);
  for (const auto& e : r.events) EXPECT_DOUBLE_EQ(r.path[e.index].lambda, e.lambda);
  for (const auto& p : r.path) EXPECT_NEAR(p.value * p.value * p.value - p.value, p.lambda, 1e-9);
  EXPECT_NEAR(r.path.back().lambda, 1.0, 0.0);
  EXPECT_LE(r.steps, o.max_steps);
  EXPECT_NE(r.message.find("reached"), std::string::npos);
}

// A target just below the first fold: the path meets it on the lower branch (the first
// crossing), even when a step straddles the fold and comes back below the target on the
// middle branch.
TEST(BvpArclength, TargetJustBelowAFoldIsMetOnTheFirstBranch) {
  for (double gap : {1e-7, 1e-3}) {
    FnSystem s = s_curve();
    Vec x = Vec::Constant(1, -1.2);
    ArclengthOptions o = s_curve_path(FoldAction::Continue);
    o.target = kFold - gap;
    const ArclengthResult r = follow(s, x, o);
    ASSERT_TRUE(r.converged()) << r.message;
    EXPECT_NEAR(x[0] * x[0] * x[0] - x[0], o.target, 1e-12);
    EXPECT_LT(x[0], -1.0 / std::sqrt(3.0)) << "landed on the middle branch";
  }
}

// The same loading path with FoldAction::Snap: at the first fold lambda turns back before the
// target, so the path jumps to the upper branch (x = 2/sqrt(3) at the fold load, a jump of
// sqrt(3)), never visits the middle branch, and ends at the same answer.
TEST(BvpArclength, SnapAtFoldLandsOnTheUpperBranch) {
  FnSystem s = s_curve();
  Vec x = Vec::Constant(1, -1.2);
  const ArclengthOptions o = s_curve_path(FoldAction::Snap);
  const ArclengthResult r = follow(s, x, o);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_NEAR(x[0], kPlastic, 1e-10);
  ASSERT_EQ(r.events.size(), 2u) << r.message;
  EXPECT_EQ(r.events[0].type, ArclengthEventType::Fold);
  EXPECT_NEAR(r.events[0].lambda, kFold, 1e-6);
  EXPECT_EQ(r.events[1].type, ArclengthEventType::Snap);
  const double landing = kFold + 1e-4 * (o.target - o.start);
  EXPECT_NEAR(r.events[1].lambda, landing, 1e-6);
  const double x_land = r.events[1].x[0];
  EXPECT_NEAR(x_land * x_land * x_land - x_land, r.events[1].lambda, 1e-10);
  EXPECT_GT(x_land, 2.0 / std::sqrt(3.0));
  EXPECT_NEAR(r.events[1].jump, std::sqrt(3.0), 1e-3);
  EXPECT_EQ(r.events[1].index, r.events[0].index + 1);
  EXPECT_EQ(r.events[1].damped_steps, 0);  // a Newton attempt landed
  for (const auto& p : r.path)  // lower branch up to the fold, then the upper branch
    EXPECT_TRUE(p.value <= -1.0 / std::sqrt(3.0) + 1e-6 || p.value >= 2.0 / std::sqrt(3.0)) << p.value;
}

// The same path with a fold_limit that names the fold a limit of the system: no snap is tried,
// the run stalls at the fold (returning the last point before it, on the lower branch) and the
// message carries the hook's reason. The hook sees the fold point itself (x^3 - x = lambda, x at
// -1/sqrt(3)).
TEST(BvpArclength, FoldNamedALimitIsNotSnapped) {
  FnSystem s = s_curve();
  Vec x = Vec::Constant(1, -1.2);
  ArclengthOptions o = s_curve_path(FoldAction::Snap);
  int calls = 0;
  double x_fold = 0.0, lambda_fold = 0.0;
  o.fold_limit = [&](const Vec& xf, double lambda) {
    ++calls;
    x_fold = xf[0];
    lambda_fold = lambda;
    return std::string("the test's limit");
  };
  const ArclengthResult r = follow(s, x, o);
  EXPECT_EQ(r.status, ArclengthStatus::Stalled);
  EXPECT_EQ(calls, 1);
  EXPECT_NEAR(x_fold, -1.0 / std::sqrt(3.0), 1e-4);
  EXPECT_NEAR(lambda_fold, kFold, 1e-6);
  EXPECT_NE(r.message.find("the test's limit"), std::string::npos) << r.message;
  for (const auto& e : r.events) EXPECT_NE(e.type, ArclengthEventType::Snap);
  EXPECT_LE(x[0], -1.0 / std::sqrt(3.0) + 1e-6);  // still on the lower branch
  EXPECT_LT(r.parameter, kFold + 1e-9);

  // A hook that returns "" lets the snap happen as before.
  Vec x2 = Vec::Constant(1, -1.2);
  o.fold_limit = [](const Vec&, double) { return std::string(); };
  const ArclengthResult r2 = follow(s, x2, o);
  ASSERT_TRUE(r2.converged()) << r2.message;
  EXPECT_NEAR(x2[0], kPlastic, 1e-10);
}

// A fold beyond which the curve never comes back: (x^2 + lambda)(x - 3) = 0 from x = -1 at
// lambda = -1 towards lambda = 1. Followed around the fold at (0, 0) the path heads back down
// the branch x = sqrt(-lambda) and leaves the parameter window (stalled, never reached); with
// snaps it jumps to the separate branch x = 3 and reaches the target there.
TEST(BvpArclength, SnapReachesADisconnectedBranch) {
  auto f = [](const Vec& x, double l, Vec& out) {
    out[0] = (x[0] * x[0] + l) * (x[0] - 3.0);
    return true;
  };
  ArclengthOptions o;
  o.start = -1.0;
  o.target = 1.0;
  {
    FnSystem s(1, f);
    Vec x = Vec::Constant(1, -1.0);
    const ArclengthResult r = follow(s, x, o);
    EXPECT_EQ(r.status, ArclengthStatus::Stalled) << r.message;
    EXPECT_FALSE(r.converged());
    EXPECT_NE(r.message.find("window"), std::string::npos) << r.message;
    ASSERT_EQ(r.count(ArclengthEventType::Fold), 1);
    EXPECT_NEAR(r.events[0].lambda, 0.0, 1e-6);
    EXPECT_NEAR((x[0] * x[0] + r.parameter) * (x[0] - 3.0), 0.0, 1e-9);  // x solves at r.parameter
  }
  {
    FnSystem s(1, f);
    Vec x = Vec::Constant(1, -1.0);
    o.at_fold = FoldAction::Snap;
    const ArclengthResult r = follow(s, x, o);
    ASSERT_TRUE(r.converged()) << r.message;
    EXPECT_NEAR(x[0], 3.0, 1e-10);
    ASSERT_EQ(r.count(ArclengthEventType::Snap), 1);
    EXPECT_NEAR(r.events[1].jump, 3.0, 1e-6);
  }
}

// Pitchfork x^3 - lambda x = 0 along the trivial branch x = 0 from lambda = -1 to 1: the
// augmented determinant changes sign at lambda = 0 (a bifurcation), the tangent's lambda
// component does not (no fold).
TEST(BvpArclength, PitchforkIsABifurcationNotAFold) {
  FnSystem s(1, [](const Vec& x, double l, Vec& f) {
    f[0] = x[0] * x[0] * x[0] - l * x[0];
    return true;
  });
  Vec x = Vec::Zero(1);
  ArclengthOptions o;
  o.start = -1.0;
  o.target = 1.0;
  const ArclengthResult r = follow(s, x, o);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(x[0], 0.0);
  EXPECT_EQ(r.count(ArclengthEventType::Fold), 0);
  ASSERT_EQ(r.count(ArclengthEventType::Bifurcation), 1) << r.message;
  EXPECT_NEAR(r.events[0].lambda, 0.0, 1e-6);
  EXPECT_TRUE(r.events[0].refined);

  // The same with bifurcation detection off.
  x.setZero();
  o.detect_bifurcations = false;
  EXPECT_TRUE(follow(s, x, o).events.empty());
}

// A linear system A x = lambda b: one predictor lands on the target and the solve there is
// exact, so one or two steps reach x = target A^-1 b.
TEST(BvpArclength, LinearSystemReachesTheTargetExactly) {
  Eigen::Matrix3d A;
  A << 4, 1, 0, 1, 3, 1, 0, 1, 2;
  const Eigen::Vector3d b(1, -2, 3);
  FnSystem s(3, [A, b](const Vec& x, double l, Vec& f) {
    f = A * x - l * b;
    return true;
  });
  Vec x = Vec::Zero(3);
  ArclengthOptions o;
  o.target = 2.0;
  o.initial_step = o.max_step = 10.0;
  const ArclengthResult r = follow(s, x, o);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LE(r.steps, 2);
  EXPECT_TRUE(r.events.empty());
  const Vec exact = A.lu().solve(2.0 * b);
  EXPECT_LT((x - exact).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_DOUBLE_EQ(r.path.back().lambda, 2.0);
}

// The corrector's system keeps the unknown scales of the system it borders (KINSOL's uscale,
// 1 / typical magnitude): an unknown declared large (scale 1e-4, typical magnitude 1e4, as
// PRB's bending-plane angle) may move by O(1) in one Newton step under a max_newton_step of 1.
// With the scales inverted (1e4: its O(1) moves looked like scaled steps of 1e4) every corrector
// step was cut to 1e-4 of that unknown and a linear path took hundreds of iterations (PRB's
// loading paths: 64 steps instead of 15 on bench_soft's E0.1x_n10_+x).
TEST(BvpArclength, CorrectorKeepsTheSystemsUnknownScales) {
  // x0 + x0^3 = 10 lambda, x1 = x0^2 - lambda: curved, so that the tangent predictor misses.
  FnSystem s(2, [](const Vec& x, double l, Vec& f) {
    f[0] = x[0] + x[0] * x[0] * x[0] - 10.0 * l;
    f[1] = x[1] - x[0] * x[0] + l;
    return true;
  });
  s.uscale = Eigen::Vector2d(1e-4, 1.0);
  Vec x = Vec::Zero(2);
  ArclengthOptions o;
  o.target = 1.0;
  NewtonOptions n;
  n.max_newton_step = 1.0;
  const ArclengthResult r = follow(s, x, o, n);
  ASSERT_TRUE(r.converged()) << r.message;
  // Measured: 39 corrector solves and 216 Newton iterations in all; with the scales inverted
  // 105 and 582.
  EXPECT_LE(r.steps, 50) << r.message;
  EXPECT_LE(r.iterations, 300) << r.message;
  EXPECT_NEAR(x[0], 2.0, 1e-10);  // 2 + 8 = 10
  EXPECT_NEAR(x[1], 3.0, 1e-10);
}

namespace {
// Two unknowns coupled through s = u + v, d = u - v: s^3 - s = lambda, d = s^2. The folds of
// the S-curve in s show in both u and v.
Residual coupled() {
  return [](const Vec& x, double l, Vec& f) {
    const double s = x[0] + x[1], d = x[0] - x[1];
    f[0] = s * s * s - s - l;
    f[1] = d - s * s;
    return true;
  };
}
void coupled_jacobian(const Vec& x, double, Eigen::MatrixXd& J) {
  const double s = x[0] + x[1], a = 3.0 * s * s - 1.0;
  J << a, a, 1.0 - 2.0 * s, -1.0 - 2.0 * s;
}
}  // namespace

// The coupled 2-D fold, with finite-difference, analytic dense and analytic sparse (KLU)
// Jacobians: the same folds to 1e-6, the same answer at the target.
TEST(BvpArclength, CoupledTwoUnknownFold) {
  const double s0 = -1.2, d0 = s0 * s0;
  ArclengthOptions o;
  o.start = s0 * s0 * s0 - s0;
  o.target = 1.0;
  for (int variant = 0; variant < 3; ++variant) {
    SCOPED_TRACE(variant);
    FnSystem sys(2, coupled(), variant > 0 ? Jacobian(coupled_jacobian) : Jacobian(), variant == 2);
    NewtonOptions no;
    if (variant == 2) no.linear_solver = tdcr::bvp::LinearSolverKind::SparseKLU;
    Vec x(2);
    x << (s0 + d0) / 2, (s0 - d0) / 2;
    const ArclengthResult r = follow(sys, x, o, no);
    ASSERT_TRUE(r.converged()) << r.message;
    EXPECT_NEAR(x[0] + x[1], kPlastic, 1e-10);
    EXPECT_NEAR(x[0] - x[1], kPlastic * kPlastic, 1e-9);
    ASSERT_EQ(r.count(ArclengthEventType::Fold), 2) << r.message;
    EXPECT_EQ(r.count(ArclengthEventType::Bifurcation), 0);
    EXPECT_NEAR(r.events[0].lambda, kFold, 1e-6);
    EXPECT_NEAR(r.events[1].lambda, -kFold, 1e-6);
    const Vec& xf = r.events[0].x;
    EXPECT_NEAR(xf[0] + xf[1], -1.0 / std::sqrt(3.0), 1e-4);
    EXPECT_NEAR(xf[0] - xf[1], 1.0 / 3.0, 1e-4);
  }
}

namespace {
// Bratu with a load parameter (the tridiagonal test problem of the bvp tests).
class BratuPath : public tdcr::bvp::ParameterizedSystem {
 public:
  BratuPath(int n, bool analytic) : b_(n, 0.0, analytic) {}
  int size() const override { return b_.size(); }
  void set_parameter(double lambda) override { b_.lambda = lambda; }
  bool residual(const Eigen::Ref<const Vec>& u, Eigen::Ref<Vec> f) override { return b_.residual(u, f); }
  const tdcr::bvp::SparsityPattern* sparsity() const override { return b_.sparsity(); }
  bool has_jacobian() const override { return b_.has_jacobian(); }
  bool sparse_jacobian(const Eigen::Ref<const Vec>& u, const Eigen::Ref<const Vec>& f, double* v) override {
    return b_.sparse_jacobian(u, f, v);
  }
  void residual_scale(Eigen::Ref<Vec> s) const override { b_.residual_scale(s); }

 private:
  bvp_test::Bratu b_;
};
}  // namespace

// Bratu towards lambda = 5, beyond its fold (3.51 for the continuous problem): the fold is
// found (grouped finite differences and the analytic sparse Jacobian agree on it to 1e-6),
// then the upper branch heads back to lambda -> 0 with growing u, so the step limit ends the
// run (never reported as reached) with x a solution at the returned parameter.
TEST(BvpArclength, BratuFoldThenStepLimit) {
  double fold[2] = {0.0, 0.0};
  for (int analytic = 0; analytic < 2; ++analytic) {
    BratuPath s(20, analytic == 1);
    Vec u = Vec::Zero(20);
    ArclengthOptions o;
    o.target = 5.0;
    o.max_steps = 60;
    const ArclengthResult r = follow(s, u, o);
    EXPECT_EQ(r.status, ArclengthStatus::StepLimit) << r.message;
    EXPECT_FALSE(r.converged());
    EXPECT_NE(r.message.find("step_limit"), std::string::npos) << r.message;
    EXPECT_EQ(r.steps, 60);
    ASSERT_EQ(r.count(ArclengthEventType::Fold), 1) << r.message;
    fold[analytic] = r.events[0].lambda;
    EXPECT_NEAR(fold[analytic], 3.5138, 0.02);
    s.set_parameter(r.parameter);
    Vec f(20);
    ASSERT_TRUE(s.residual(u, f));
    EXPECT_LT(f.cwiseAbs().maxCoeff() * 21 * 21, 1e-9);
  }
  EXPECT_NEAR(fold[0], fold[1], 1e-6);
}

// Failures: a residual that cannot be evaluated beyond lambda = 0.5 (an integrator giving up)
// stalls with the reason; a start x that solves nothing is refused; neither is "reached".
TEST(BvpArclength, NonConvergenceIsReported) {
  FnSystem s(1, [](const Vec& x, double l, Vec& f) {
    if (l > 0.5) return false;
    f[0] = x[0] - l;
    return true;
  });
  Vec x = Vec::Zero(1);
  const ArclengthResult r = follow(s, x, ArclengthOptions());
  EXPECT_EQ(r.status, ArclengthStatus::Stalled);
  EXPECT_FALSE(r.converged());
  EXPECT_NE(r.message.find("min_step"), std::string::npos) << r.message;
  EXPECT_LE(r.parameter, 0.5);
  EXPECT_GT(r.parameter, 0.49);
  EXPECT_NEAR(x[0], r.parameter, 1e-12);

  FnSystem none(1, [](const Vec& x, double l, Vec& f) {
    f[0] = x[0] * x[0] + 1.0 + l * l;
    return true;
  });
  Vec y = Vec::Constant(1, 0.3);
  const ArclengthResult q = follow(none, y, ArclengthOptions());
  EXPECT_EQ(q.status, ArclengthStatus::Stalled);
  EXPECT_FALSE(q.converged());
  EXPECT_NE(q.message.find("start"), std::string::npos) << q.message;
  EXPECT_EQ(y[0], 0.3);
  EXPECT_EQ(none.accepted, 0);
}

// Inconsistent options name their field.
TEST(BvpArclength, OptionsValidationNamesTheField) {
  auto field_of = [](const std::function<void(ArclengthOptions&)>& set) -> std::string {
    ArclengthOptions o;
    set(o);
    try {
      o.validate();
    } catch (const tdcr::InputError& e) {
      return e.field();
    }
    return "";
  };
  EXPECT_EQ(field_of([](ArclengthOptions&) {}), "");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.target = o.start; }), "arclength.target");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.start = NAN; }), "arclength.start");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.min_step = -1.0; }), "arclength.min_step");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.min_step = 0.1; }), "arclength.min_step");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.initial_step = 1.0; }), "arclength.initial_step");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.growth = 0.5; }), "arclength.growth");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.shrink = 1.0; }), "arclength.shrink");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.max_turn = 4.0; }), "arclength.max_turn");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.max_steps = 0; }), "arclength.max_steps");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.window = -1.0; }), "arclength.window");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.event_tolerance = 0.0; }), "arclength.event_tolerance");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.snap_overshoot = 2.0; }), "arclength.snap_overshoot");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.snap_perturbation = 0.0; }), "arclength.snap_perturbation");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.snap_tries = 0; }), "arclength.snap_tries");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.snap_max_iterations = 0; }), "arclength.snap_max_iterations");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.damped_landing_steps = -1; }), "arclength.damped_landing_steps");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.damped_landing_rate = 0.0; }), "arclength.damped_landing_rate");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.damped_landing_move = -1.0; }), "arclength.damped_landing_move");
  EXPECT_EQ(field_of([](ArclengthOptions& o) { o.corrector_max_iterations = 0; }),
            "arclength.corrector_max_iterations");

  // arclength_continuation() validates too, before touching x.
  FnSystem s = s_curve();
  Vec x = Vec::Zero(1);
  ArclengthOptions o;
  o.shrink = 0.0;
  NewtonSolver newton;
  EXPECT_THROW(tdcr::bvp::arclength_continuation(newton, s, x, NewtonOptions(), o), tdcr::InputError);
  EXPECT_EQ(s.evaluations, 0);
}

TEST(BvpArclength, NamesOfStatusesAndEvents) {
  EXPECT_EQ(tdcr::bvp::to_string(ArclengthStatus::Reached), "reached");
  EXPECT_EQ(tdcr::bvp::to_string(ArclengthStatus::Stalled), "stalled");
  EXPECT_EQ(tdcr::bvp::to_string(ArclengthStatus::StepLimit), "step_limit");
  EXPECT_EQ(tdcr::bvp::to_string(ArclengthEventType::Fold), "fold");
  EXPECT_EQ(tdcr::bvp::to_string(ArclengthEventType::Bifurcation), "bifurcation");
  EXPECT_EQ(tdcr::bvp::to_string(ArclengthEventType::Snap), "snap");
}

// ArclengthOptions::corrector_freeze_jacobian_below: correctors that freeze their Jacobian near
// the solution find the same path (Bratu up to lambda = 3, its fold at 3.51 and the folds of the
// coupled S-curve to 1e-6) with fewer Jacobians than exact-Newton correctors.
TEST(BvpArclength, FrozenCorrectorJacobiansFindTheSamePathWithFewerJacobians) {
  int jacobians[2] = {0, 0};
  Vec end[2];
  double fold[2] = {0.0, 0.0};
  for (int frozen = 0; frozen < 2; ++frozen) {
    SCOPED_TRACE(frozen);
    ArclengthOptions o;
    o.corrector_freeze_jacobian_below = frozen ? 1e-3 : 0.0;
    BratuPath s(20, false);
    Vec u = Vec::Zero(20);
    o.target = 3.0;
    const ArclengthResult r = follow(s, u, o);
    ASSERT_TRUE(r.converged()) << r.message;
    jacobians[frozen] = r.jacobian_evaluations;
    end[frozen] = u;
    BratuPath b(20, false);
    Vec v = Vec::Zero(20);
    o.target = 5.0;
    o.max_steps = 60;
    const ArclengthResult rf = follow(b, v, o);
    ASSERT_EQ(rf.count(ArclengthEventType::Fold), 1) << rf.message;
    fold[frozen] = rf.events[0].lambda;
  }
  EXPECT_LT(jacobians[1], jacobians[0]);
  EXPECT_LE((end[1] - end[0]).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(fold[1], fold[0], 1e-6);
  ArclengthOptions bad;
  bad.corrector_freeze_jacobian_below = -1.0;
  EXPECT_THROW(bad.validate(), tdcr::InputError);
  tdcr::SolverOptions no_reuse;
  no_reuse.reuse_jacobian = false;
  EXPECT_EQ(tdcr::detail::arclength_options(no_reuse).corrector_freeze_jacobian_below, 0.0);
  EXPECT_GT(tdcr::detail::arclength_options(tdcr::SolverOptions()).corrector_freeze_jacobian_below, 0.0);
}

namespace {
// One state a = ref + sin(w) with the unknown w in a chart around ref that degenerates at
// |w| = pi / 2, and F = a - 3 lambda: a moves by 3 along the path, three times what one chart
// covers. recenter() folds w into ref once |w| > 0.5 (VCref's disk rotation charts, in one
// dimension).
class ChartSystem : public tdcr::bvp::ParameterizedSystem {
 public:
  explicit ChartSystem(bool recentre) : recentre_(recentre) {}
  int size() const override { return 1; }
  void set_parameter(double lambda) override { lambda_ = lambda; }
  bool residual(const Eigen::Ref<const Vec>& x, Eigen::Ref<Vec> f) override {
    f[0] = ref + std::sin(x[0]) - 3.0 * lambda_;
    return true;
  }
  bool recenter(Eigen::Ref<Vec> x) override {
    if (!recentre_ || std::abs(x[0]) <= 0.5) return false;
    ref += std::sin(x[0]);
    x[0] = 0.0;
    ++recentred;
    return true;
  }
  double ref = 0.0;
  int recentred = 0;

 private:
  bool recentre_;
  double lambda_ = 0.0;
};
}  // namespace

// A chart that degenerates along the path looks like a fold in its coordinates (dF/dw = cos w
// vanishes at a = ref + 1); re-centred at accepted points the path is regular to the target.
TEST(BvpArclength, RecentredChartsKeepThePathRegular) {
  ChartSystem s(true);
  Vec x = Vec::Zero(1);
  ArclengthOptions o;
  o.target = 1.0;
  const ArclengthResult r = follow(s, x, o);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_TRUE(r.events.empty()) << r.message;
  EXPECT_GE(s.recentred, 3);  // measured: 4
  EXPECT_NEAR(s.ref + std::sin(x[0]), 3.0, 1e-10);
  // Without re-centring the chart's edge stops the path (a fold at a = 1, a third of the way).
  ChartSystem fixed(false);
  Vec y = Vec::Zero(1);
  const ArclengthResult q = follow(fixed, y, o);
  EXPECT_FALSE(q.converged() && q.events.empty()) << q.message;
}

namespace {

// F = (x^3 - x - lambda, y): the gradient of V = x^4 / 4 - x^2 / 2 - lambda x + y^2 / 2, with a
// fold at lambda = 2 / (3 sqrt 3), x = -1 / sqrt 3, past which only the right branch is left;
// viscous damping as ParameterizedSystem::set_damping describes. Residuals fail for x > `wall`
// (a limit of the system, as a tendon reaching the backbone).
class DampedCubic : public tdcr::bvp::ParameterizedSystem {
 public:
  explicit DampedCubic(double wall = INFINITY) : wall_(wall), ref_(Vec::Zero(2)) {}
  int size() const override { return 2; }
  void set_parameter(double lambda) override { lambda_ = lambda; }
  bool residual(const Eigen::Ref<const Vec>& x, Eigen::Ref<Vec> f) override {
    if (x[0] > wall_) return false;
    f << x[0] * x[0] * x[0] - x[0] - lambda_, x[1];
    f += rate_ * (x - ref_);
    return true;
  }
  bool set_damping(const Eigen::Ref<const Vec>& x_ref, double rate) override {
    ref_ = x_ref;
    rate_ = rate;
    ++damping_calls;
    return true;
  }
  int damping_calls = 0;

 private:
  double wall_, lambda_ = 0.0, rate_ = 0.0;
  Vec ref_;
};

// Newton attempts from the fold that cannot land (one iteration each, a tiny perturbation).
ArclengthOptions hopeless_newton_snaps() {
  ArclengthOptions o;
  o.start = -1.0;
  o.target = 1.0;
  o.at_fold = FoldAction::Snap;
  o.snap_tries = 1;
  o.snap_max_iterations = 1;
  o.snap_perturbation = 1e-9;
  return o;
}

const double kLeftRoot = -1.324717957244746;  // x^3 - x + 1 = 0

}  // namespace

TEST(BvpArclength, DampedMotionLandsWhereNewtonAttemptsCannot) {
  const double right_root = 1.324717957244746;  // x^3 - x - 1 = 0: the answer at lambda = 1
  {
    DampedCubic sys;
    NewtonSolver newton;
    Vec x(2);
    x << kLeftRoot, 0.0;
    ArclengthOptions o = hopeless_newton_snaps();
    o.damped_landing_steps = 0;  // without the damped motion the snap stalls
    const ArclengthResult r = tdcr::bvp::arclength_continuation(newton, sys, x, NewtonOptions(), o);
    EXPECT_EQ(r.status, ArclengthStatus::Stalled);
    EXPECT_NE(r.message.find("no Newton solve past the fold"), std::string::npos) << r.message;
  }
  DampedCubic sys;
  NewtonSolver newton;
  Vec x(2);
  x << kLeftRoot, 0.0;
  const ArclengthResult r = tdcr::bvp::arclength_continuation(newton, sys, x, NewtonOptions(), hopeless_newton_snaps());
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_GT(sys.damping_calls, 2);
  ASSERT_EQ(r.count(ArclengthEventType::Fold), 1);
  ASSERT_EQ(r.count(ArclengthEventType::Snap), 1);
  EXPECT_NEAR(r.events[0].lambda, 2.0 / (3.0 * std::sqrt(3.0)), 1e-6);
  EXPECT_GT(r.events[1].damped_steps, 1);  // the snap says how it landed
  EXPECT_EQ(r.events[0].damped_steps, 0);
  EXPECT_NEAR(x[0], right_root, 1e-9);  // the stable branch the motion comes to rest on
  EXPECT_NEAR(x[1], 0.0, 1e-12);
  EXPECT_TRUE(r.limit.empty());
  // The damping is off again: the residual at the answer is the system's own.
  Vec f(2);
  sys.set_parameter(1.0);
  ASSERT_TRUE(sys.residual(x, f));
  EXPECT_LT(f.norm(), 1e-9);
}

TEST(BvpArclength, DampedMotionIntoALimitNamesIt) {
  DampedCubic sys(/*wall=*/0.5);
  NewtonSolver newton;
  Vec x(2);
  x << kLeftRoot, 0.0;
  ArclengthOptions o = hopeless_newton_snaps();
  o.fold_limit = [](const Vec& xf, double) { return xf[0] > 0.45 ? std::string("x at its wall") : std::string(); };
  const ArclengthResult r = tdcr::bvp::arclength_continuation(newton, sys, x, NewtonOptions(), o);
  EXPECT_EQ(r.status, ArclengthStatus::Stalled);
  EXPECT_EQ(r.limit, "x at its wall");
  EXPECT_NE(r.message.find("runs into a limit"), std::string::npos) << r.message;
  // The returned state is the path's last equilibrium on the first branch, not the wall.
  EXPECT_LT(x[0], -1.0 / std::sqrt(3.0));
  EXPECT_NEAR(x[0] * x[0] * x[0] - x[0], r.parameter, 1e-9);
}

namespace {

// F = grad V, V = x^4 / 4 - x^2 / 2 - lambda x + y^4 / 4 - x y^2 / 2 - eps y: the cubic's fold at
// lambda = 2 / (3 sqrt 3), and past it, where x > 0, the equilibrium near y = 0 is a saddle (the
// y-stiffness 3 y^2 - x is negative) between two minima at y^2 ~ x. eps, a small imperfection,
// tips the structure's motion towards y > 0. Newton attempts from the fold, perturbed along the
// null vector (along x), stay near y = 0 and converge to the saddle.
class SaddleBeyondFold : public tdcr::bvp::ParameterizedSystem {
 public:
  static constexpr double kEps = 1e-3;
  int size() const override { return 2; }
  void set_parameter(double lambda) override { lambda_ = lambda; }
  bool residual(const Eigen::Ref<const Vec>& x, Eigen::Ref<Vec> f) override {
    f << x[0] * x[0] * x[0] - x[0] - lambda_ - 0.5 * x[1] * x[1], x[1] * x[1] * x[1] - x[0] * x[1] - kEps;
    f += rate_ * (x - ref_);
    return true;
  }
  bool set_damping(const Eigen::Ref<const Vec>& x_ref, double rate) override {
    ref_ = x_ref;
    rate_ = rate;
    return true;
  }
  // The Hessian of V (the undamped Jacobian) is positive definite.
  static bool stable(const Vec& x) {
    Eigen::Matrix2d H;
    H << 3.0 * x[0] * x[0] - 1.0, -x[1], -x[1], 3.0 * x[1] * x[1] - x[0];
    return H.determinant() > 0.0 && H.trace() > 0.0;
  }

 private:
  double lambda_ = 0.0, rate_ = 0.0;
  Vec ref_ = Vec::Zero(2);
};

ArclengthOptions saddle_path() {
  ArclengthOptions o;
  o.start = -1.0;
  o.target = 1.0;
  o.at_fold = FoldAction::Snap;
  return o;
}

Vec saddle_start() {  // the stable equilibrium at lambda = -1 near (kLeftRoot, 0), by Newton
  SaddleBeyondFold s;
  s.set_parameter(-1.0);
  Vec x(2);
  x << kLeftRoot, 0.0;
  NewtonSolver newton;
  EXPECT_TRUE(newton.solve(s, x, NewtonOptions()).converged());
  return x;
}

}  // namespace

// Without a landing test the snap lands on the saddle (Newton's nearest root) and the path goes
// on along it to the target: an equilibrium the structure would not stay at.
TEST(BvpArclength, SnapWithoutLandingTestCanLandOnASaddle) {
  SaddleBeyondFold sys;
  NewtonSolver newton;
  Vec x = saddle_start();
  const ArclengthResult r = tdcr::bvp::arclength_continuation(newton, sys, x, NewtonOptions(), saddle_path());
  ASSERT_TRUE(r.converged()) << r.message;
  ASSERT_EQ(r.count(ArclengthEventType::Snap), 1);
  EXPECT_LT(std::abs(x[1]), 0.01);
  EXPECT_FALSE(SaddleBeyondFold::stable(x));
  EXPECT_EQ(r.rejected_landings, 0);
}

// With accept_landing rejecting unstable landings, every Newton attempt (all at the saddle) is
// rejected, and the damped motion from the fold leaves the saddle towards y > 0 and lands on the
// minimum there; the path reaches the target on that branch.
TEST(BvpArclength, RejectedLandingsLeaveTheSnapToTheDampedMotion) {
  SaddleBeyondFold sys;
  NewtonSolver newton;
  Vec x = saddle_start();
  ArclengthOptions o = saddle_path();
  int tests = 0;
  o.accept_landing = [&tests](const Vec& xl, double) {
    ++tests;
    return SaddleBeyondFold::stable(xl) ? std::string() : std::string("a saddle");
  };
  const ArclengthResult r = tdcr::bvp::arclength_continuation(newton, sys, x, NewtonOptions(), o);
  ASSERT_TRUE(r.converged()) << r.message;
  ASSERT_EQ(r.count(ArclengthEventType::Snap), 1);
  EXPECT_GE(r.rejected_landings, 1);
  EXPECT_EQ(tests, r.rejected_landings + 1);  // the accepted landing was tested too
  EXPECT_NE(r.message.find("snap landings rejected (last: a saddle)"), std::string::npos) << r.message;
  EXPECT_GT(r.events[1].damped_steps, 0);
  EXPECT_TRUE(SaddleBeyondFold::stable(x));
  // The minimum at lambda = 1: y^3 - x y = eps and x^3 - x - 1 = y^2 / 2, y > 0.
  EXPECT_GT(x[1], 1.0);
  EXPECT_NEAR(x[1] * x[1] * x[1] - x[0] * x[1], SaddleBeyondFold::kEps, 1e-9);
  EXPECT_NEAR(x[0] * x[0] * x[0] - x[0] - 1.0, 0.5 * x[1] * x[1], 1e-9);
}

// A test that rejects every landing: the snap stalls and says why, with the last reason.
TEST(BvpArclength, EveryLandingRejectedStallsTheSnap) {
  SaddleBeyondFold sys;
  NewtonSolver newton;
  Vec x = saddle_start();
  ArclengthOptions o = saddle_path();
  o.accept_landing = [](const Vec&, double) { return std::string("the test rejects it"); };
  const ArclengthResult r = tdcr::bvp::arclength_continuation(newton, sys, x, NewtonOptions(), o);
  EXPECT_EQ(r.status, ArclengthStatus::Stalled);
  EXPECT_EQ(r.count(ArclengthEventType::Snap), 0);
  EXPECT_GE(r.rejected_landings, 2);
  EXPECT_NE(r.message.find("came to rest only at rejected landings (last: the test rejects it)"), std::string::npos)
      << r.message;
  EXPECT_LT(x[0], -1.0 / std::sqrt(3.0) + 1e-6);  // the last equilibrium before the fold
}
