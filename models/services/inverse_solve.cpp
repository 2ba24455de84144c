// Inverse solve (inverse_solve.hpp; method and limits in docs/user-guide.md, "Inverse solve").
//
// The problem: min |T|^2 / 2 over T >= 0 subject to e(T) = 0, e the (weighted) tip error. Phase 1
// finds a feasible T (bounded Levenberg-Marquardt on |e|^2); phase 2 is a feasible reduced-space
// SQP: at a point on the target with free (pulling) tendons F, the multipliers lambda solve
// T_F = J_F^T lambda in the least-squares sense, Z spans the null space of J_F (the tangent space
// of the target), g = Z^T T_F is the reduced gradient and B = Z^T (I - sum lambda_i d2 e_i) Z the
// reduced Hessian of the Lagrangian (its curvature term by differences of J along Z). The Newton
// step Z B^-1 g is followed by Gauss-Newton corrections back onto the target; the Lagrangian with
// the step's multipliers is the merit (insensitive, to first order, to the corrections' residual
// error). Tensions that reach zero are fixed there; a fixed tension whose multiplier
// mu_i = -J_i^T lambda is negative is freed. Phase 1 that ends at a local minimum of the distance
// (or stalls) starts again from other tensions; the answer is finally solved cold, along the
// loading path, and accepted only if that meets the target too. Every Jacobian is one by central
// differences of tight, warm-started forward solves (kDifferenceStep), so that the optimality
// conditions that end phase 2 are checked to about 1e-8 relative.
#include "tdcr/models/inverse_solve.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Function tolerance of the inner forward solves (at most): the tips of warm and cold solves then
// agree to 1e-12 m or better (the paper robot, every model, n = 5..20, E and E / 10; at 1e-10 they
// differ by up to 1e-10 m), three orders below the default position tolerance.
constexpr double kInnerFunctionTolerance = 1e-12;
// Function tolerance of the forward solves that difference the Jacobian and of phase 2's (where
// they converge, else kInnerFunctionTolerance): their tips agree to about 1e-15 m.
constexpr double kDifferenceFunctionTolerance = 1e-14;
// Tip scatter (m) below which two differences are not told apart (consistency of a column).
constexpr double kTipNoise = 1e-12;
// Relative rank threshold of a Jacobian (singular values below it times the largest are zero): a
// planar robot's out-of-plane row is zero to 1e-17, a near-singular pose's smallest singular
// value is 1e-5 of the largest.
constexpr double kRankThreshold = 1e-8;
// Central-difference increment of the Jacobian, relative to max(T_j, tension scale). Its
// truncation error, not the tips' noise, limits the reduced gradient where a target coordinate
// is barely controllable (a tip force across the bending plane of the paper robot: singular
// values 1.6e-2, 4.8e-5, 3.6e-6 m/N): there 1e-3 errs by 1e-5 N, 1e-4 by 1e-7 N. (The models'
// differential kinematics is no alternative: it costs 5 to 17 warm solves, as it also forms the
// tip compliance, and VCref's is accurate to only 5e-7 .. 2e-4 relative on the paper robot, its
// shooting Jacobian being a forward difference.)
constexpr double kDifferenceStep = 1e-4;
// Increment of the reduced Hessian's second differences along a tangent direction, relative to
// max(|T|, tension scale): truncation (delta / T_c)^2 ~ 1e-5 and the tips' noise times the
// multipliers over delta^2 both stay far below B's own scale (that of I).
constexpr double kHessianStep = 1e-2;
// Gauss-Newton corrections back onto the target after a step, and how close to it they bring the
// tip (times the tolerance): the merit's error term, second order in this, then stays below the
// gain of a step of the tensions' resolution.
constexpr int kCorrections = 8;
constexpr double kRestoreFraction = 1e-2;
// Eigenvalues of the reduced Hessian below this are not positive (its scale is that of I).
constexpr double kCurvatureFloor = 1e-6;
// Steps in a row kept although their gain is below the merit's noise.
constexpr int kUnseenSteps = 3;
// Restarts of phase 1 from the cold answer when the warm-started iteration met the target on an
// equilibrium that the loading path does not reach.
constexpr int kBranchRestarts = 2;
// Other starts of phase 1 where it ends at a local minimum of the distance, the Halton points
// they are chosen from, and the bases of that sequence (one per tendon, cycled).
constexpr int kRestarts = 8;
constexpr int kCandidates = 32;
// Kept steps of phase 1 over which the error must at least halve (else another start is tried):
// Gauss-Newton halves it at every step even at a singular root.
constexpr std::size_t kStallSteps = 10;
constexpr std::array<int, 12> kPrimes = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37};

// Lawson-Hanson non-negative least squares: argmin |A y - b| over y >= 0. Every A used here
// holds a scaled identity block (full column rank), so the answer is unique.
VectorXd nnls(const MatrixXd& A, const VectorXd& b) {
  const int n = static_cast<int>(A.cols());
  VectorXd y = VectorXd::Zero(n), z(n);
  std::vector<bool> passive(static_cast<std::size_t>(n), false);
  const double tol = 10.0 * std::numeric_limits<double>::epsilon() * n * A.cwiseAbs().maxCoeff() *
                     std::max(b.norm(), std::numeric_limits<double>::min());
  VectorXd w = A.transpose() * (b - A * y);
  for (int outer = 0; outer < 3 * n; ++outer) {
    int j = -1;
    double best = tol;
    for (int i = 0; i < n; ++i)
      if (!passive[static_cast<std::size_t>(i)] && w[i] > best) best = w[(j = i)];
    if (j < 0) break;
    passive[static_cast<std::size_t>(j)] = true;
    for (int inner = 0; inner < 3 * n; ++inner) {
      std::vector<int> P;
      for (int i = 0; i < n; ++i)
        if (passive[static_cast<std::size_t>(i)]) P.push_back(i);
      MatrixXd AP(A.rows(), static_cast<Eigen::Index>(P.size()));
      for (std::size_t k = 0; k < P.size(); ++k) AP.col(static_cast<Eigen::Index>(k)) = A.col(P[k]);
      const VectorXd zP = AP.colPivHouseholderQr().solve(b);
      z.setZero();
      for (std::size_t k = 0; k < P.size(); ++k) z[P[k]] = zP[static_cast<Eigen::Index>(k)];
      double alpha = 1.0;
      for (int i : P)
        if (z[i] <= 0.0) alpha = std::min(alpha, y[i] / (y[i] - z[i]));
      if (alpha >= 1.0) {
        y = z;
        break;
      }
      y += alpha * (z - y);
      const double zero = 1e-14 * y.cwiseAbs().maxCoeff();  // rounding of the blocking variable
      for (int i : P)
        if (y[i] <= zero) {
          passive[static_cast<std::size_t>(i)] = false;
          y[i] = 0.0;
        }
    }
    w = A.transpose() * (b - A * y);
  }
  return y.cwiseMax(0.0);
}

// The damped step from T over the tendons in `free` (the others stay at their value):
// argmin |J (y - T) + e|^2 + lambda |y - T|^2 over y >= 0.
VectorXd damped_step(const MatrixXd& J, const VectorXd& e, const VectorXd& T, double lambda,
                     const std::vector<int>& free, double beta = 0.0) {
  const Eigen::Index k = J.rows(), f = static_cast<Eigen::Index>(free.size());
  VectorXd y = T;
  if (f == 0) return y;
  const Eigen::Index z = beta > 0.0 ? f : 0;
  MatrixXd A(k + f + z, f);
  VectorXd b(k + f + z), TF(f);
  const double s = std::sqrt(lambda);
  A.middleRows(k, f) = s * MatrixXd::Identity(f, f);
  if (z > 0) A.bottomRows(z) = std::sqrt(beta) * MatrixXd::Identity(f, f);
  for (Eigen::Index c = 0; c < f; ++c) {
    A.col(c).head(k) = J.col(free[static_cast<std::size_t>(c)]);
    TF[c] = T[free[static_cast<std::size_t>(c)]];
  }
  b.head(k) = A.topRows(k) * TF - e;
  b.segment(k, f) = s * TF;
  b.tail(z).setZero();
  const VectorXd yF = nnls(A, b);
  for (Eigen::Index c = 0; c < f; ++c) y[free[static_cast<std::size_t>(c)]] = yF[c];
  return y;
}

std::vector<int> all_tendons(Eigen::Index m) {
  std::vector<int> v(static_cast<std::size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) v[static_cast<std::size_t>(i)] = static_cast<int>(i);
  return v;
}

// Smallest damping: keeps the step problem strictly convex without biasing it.
double lambda_floor(const MatrixXd& J) {
  return 1e-12 * std::max(J.colwise().squaredNorm().maxCoeff(), std::numeric_limits<double>::min());
}

// Pose difference a - b: position difference and the rotation vector of R_a R_b^T (base frame).
Eigen::Matrix<double, 6, 1> pose_difference(const Frame& a, const Frame& b) {
  Eigen::Matrix<double, 6, 1> d;
  d << a.p - b.p, lie::log_so3(a.R * b.R.transpose());
  return d;
}

// One forward solve and the target error it gives.
struct Point {
  Solution solution;
  VectorXd T;  // tensions
  VectorXd e;  // weighted error: position (m), then rotation weight x rotation vector
  MatrixXd J;  // d e / d T; empty if not computed
  double position_error = 0.0;
  double rotation_error = 0.0;
  bool reached = false;  // within both tolerances
  double merit() const { return e.norm(); }
};

// The target set's local structure at a point, over the free tendons F: J_F = U S V^T of rank r,
// the multipliers lambda (T_F = J_F^T lambda, least squares), the tangent basis Z = V(:, r:), the
// reduced gradient g = Z^T T_F and the multipliers mu_i = -J_i^T lambda of the fixed tendons.
struct Structure {
  std::vector<int> free;
  MatrixXd Z;        // |F| x q
  VectorXd lambda;   // k
  VectorXd g;        // q
  VectorXd mu;       // m (entries of free tendons 0)
  MatrixXd JF;       // k x |F|
  double sigma_min = 0.0;  // smallest nonzero singular value of J_F (0 if none)
};

Structure structure(const MatrixXd& J, const VectorXd& T, const std::vector<int>& free) {
  Structure s;
  s.free = free;
  const Eigen::Index k = J.rows(), f = static_cast<Eigen::Index>(free.size()), m = T.size();
  s.JF.resize(k, f);
  VectorXd TF(f);
  for (Eigen::Index c = 0; c < f; ++c) {
    s.JF.col(c) = J.col(free[static_cast<std::size_t>(c)]);
    TF[c] = T[free[static_cast<std::size_t>(c)]];
  }
  s.lambda = VectorXd::Zero(k);
  Eigen::Index r = 0;
  MatrixXd V = MatrixXd::Identity(f, f);
  if (f > 0) {
    const Eigen::JacobiSVD<MatrixXd> svd(s.JF, Eigen::ComputeThinU | Eigen::ComputeFullV);
    const VectorXd& sv = svd.singularValues();
    while (r < sv.size() && sv[r] > kRankThreshold * sv[0]) ++r;
    if (r > 0) s.sigma_min = sv[r - 1];
    V = svd.matrixV();
    s.lambda = svd.matrixU().leftCols(r) * (V.leftCols(r).transpose() * TF).cwiseQuotient(sv.head(r));
  }
  s.Z = V.rightCols(f - r);
  s.g = s.Z.transpose() * TF;
  s.mu = -(J.transpose() * s.lambda);
  for (int i : free) s.mu[i] = 0.0;
  (void)m;
  return s;
}

class Solver {
 public:
  Solver(const StaticModel& model, ModelWorkspace& ws, const ModelInput& start, const InverseTarget& target,
         const SolverOptions& solver, const InverseOptions& options, InverseResult& result)
      : model_(model), ws_(ws), input_(start), target_(target), options_(options), r_(result) {
    // Warm-started solves reuse the workspace's last Newton Jacobian: at these tolerances their
    // answers still agree to 1e-13 m, and the differences of the Jacobian cost a few residuals.
    // The options made concrete for this robot (a 0 tolerance is tied to the robot's length),
    // and one RK4 mesh for every inner solve: their answers are differenced, and an
    // accuracy-driven solve may end on another mesh at a neighbouring input. The fixed mesh's
    // default (8 steps per disk interval, h <= 1 mm) is within 7e-10 m of CVODE on the paper
    // robot at n = 10.
    SolverOptions given = solver.resolved(model.robot().total_length());
    if (given.integrator == IntegratorKind::AccuracyDrivenRK4) given.integrator = IntegratorKind::FixedStepRK4;
    warm_ = given;
    warm_.function_tolerance = std::min(given.function_tolerance, kInnerFunctionTolerance);
    warm_.reuse_jacobian = true;
    warm_.extrapolate_warm_starts = false;
    warm_.stability = StabilityCheck::Never;
    warm_.differential_kinematics = false;
    // A trial point is warm-started next to an answer: if it fails directly, the step is too
    // long (rejected and shortened), not worth a load continuation.
    warm_.continuation = false;
    cold_ = warm_;
    cold_.continuation = solver.continuation;
    cold_.reuse_jacobian = false;
    tight_ = warm_;
    tight_.function_tolerance = std::min(given.function_tolerance, kDifferenceFunctionTolerance);
    tight_cold_ = cold_;
    tight_cold_.function_tolerance = tight_.function_tolerance;
    final_ = cold_;
    final_.stability = solver.stability;
    final_.differential_kinematics = solver.differential_kinematics;
    if (target.rotation) {
      R_target_ = lie::exp_so3(*target.rotation);
      rotation_weight_ = target.rotation_weight > 0.0 ? target.rotation_weight : model.robot().total_length();
    }
    // Tension scale: a tenth of the tension that bends the robot by a radian (EI / (r L)), or the
    // largest start tension.
    const Robot& robot = model.robot();
    double r = 0.0;
    for (const Segment& seg : robot.segments)
      for (const TendonSpec& t : seg.tendons) r = std::max(r, std::hypot(t.x, t.y));
    const double EI = robot.backbone.effective_stiffness().EI, L = robot.total_length();
    tension_scale_ = r > 0.0 && L > 0.0 && EI > 0.0 ? 0.1 * EI / (r * L) : 1.0;
    for (double t : start.actuation.values) input_start_max_ = std::max(input_start_max_, t);
    tension_scale_ = std::max(tension_scale_, input_start_max_);
  }

  void run() {
    Point cur;
    const std::vector<double>& t0 = input_.actuation.values;
    const VectorXd T0 = Eigen::Map<const VectorXd>(t0.data(), static_cast<Eigen::Index>(t0.size()));
    if (!evaluate(T0, nullptr, cur) || !jacobian(cur)) {
      finish(cur, InverseStatus::ForwardFailed,
             "the forward solve at the start tensions failed: " + cur.solution.summary.brief_report());
      return;
    }
    for (int round = 0;; ++round) {
      if (!reach(cur)) return;
      minimise_norm(cur);
      // The answer of tdcr::solve at these tensions: from the straight robot along the loading path.
      Point cold;
      const bool ok = evaluate(cur.T, nullptr, cold, Mode::Step, &final_);
      if (ok && cold.reached) {
        finish(cold, InverseStatus::Converged, std::move(message_));
        return;
      }
      if (!ok) {
        finish(cur, InverseStatus::ForwardFailed,
               "the target is met, but the forward solve from the straight robot at these tensions failed: " +
                   cold.solution.summary.brief_report());
        return;
      }
      if (round == kBranchRestarts) {
        char buf[200];
        std::snprintf(buf, sizeof buf,
                      "the target is met only on an equilibrium that the loading path from the straight robot does "
                      "not reach (there the tip is %.3g m off)",
                      cold.position_error);
        finish(cold, InverseStatus::Unreachable, buf);
        return;
      }
      cur = std::move(cold);  // the loading path's answer: go on from there
      if (!jacobian(cur)) {
        finish(cur, InverseStatus::ForwardFailed, "the Jacobian by differences of forward solves could not be formed");
        return;
      }
    }
  }

 private:
  enum class Reach { Reached, Stationary, Stalled, Limit, Failed };

  // Phase 1 from cur and, where it ends at a local minimum of the distance that misses the
  // target (or stalls), from up to kRestarts other starts: of the first kCandidates points of a
  // Halton sequence in [0, box]^m, box = max(10 tension scale, 2 max T_start), each time the one
  // farthest from the starts tried and where they ended (a target on a branch that the start's
  // valley does not lead to: a tip force across the bending plane). True when reached (cur
  // there); else the result is finished with the closest pose of all.
  bool reach(Point& cur) {
    const VectorXd T_first = cur.T;
    std::string why;
    Reach how = reach_target(cur, why);
    if (how == Reach::Reached) return true;
    Point best = std::move(cur);
    const Eigen::Index m = best.T.size();
    const double box = std::max(10.0 * tension_scale_, 2.0 * input_start_max_);
    int tried = 0;
    auto local = [](Reach h) { return h == Reach::Stationary || h == Reach::Stalled; };
    Reach best_how = how;
    // Candidates: the first kCandidates Halton points; each start the one farthest from the
    // points tried so far and where they ended (maximin).
    std::vector<VectorXd> candidates, seen = {T_first, best.T};
    for (int k = 1; k <= kCandidates; ++k) {
      VectorXd c(m);
      for (Eigen::Index i = 0; i < m; ++i) c[i] = box * halton(k, kPrimes[static_cast<std::size_t>(i) % kPrimes.size()]);
      candidates.push_back(c);
    }
    for (int k = 1; local(how) && k <= kRestarts; ++k) {
      std::size_t pick = 0;
      double far = -1.0;
      for (std::size_t c = 0; c < candidates.size(); ++c) {
        double d = std::numeric_limits<double>::infinity();
        for (const VectorXd& v : seen) d = std::min(d, (candidates[c] - v).norm());
        if (d > far) {
          far = d;
          pick = c;
        }
      }
      const VectorXd T = candidates[pick];
      candidates.erase(candidates.begin() + static_cast<std::ptrdiff_t>(pick));
      seen.push_back(T);
      Point p;
      ++tried;
      if (!evaluate(T, nullptr, p) || !jacobian(p)) continue;
      std::string w;
      how = reach_target(p, w);
      seen.push_back(p.T);
      if (how == Reach::Reached) {
        cur = std::move(p);
        return true;
      }
      if (how == Reach::Failed) {  // this start went where the forward solve fails: next one
        how = Reach::Stationary;
        continue;
      }
      if (p.merit() < best.merit()) {
        best = std::move(p);
        why = w;
        best_how = how;
      }
      if (how == Reach::Limit) {
        best_how = how;
        why = w + " (" + std::to_string(tried) + " other starts tried): the closest pose found";
      }
    }
    if (tried > 0 && local(how)) why += "; " + std::to_string(tried) + " other starts did not reach it either";
    finish(best, best_how == Reach::Stationary ? InverseStatus::Unreachable
                 : best_how == Reach::Failed   ? InverseStatus::ForwardFailed
                                               : InverseStatus::MaxIterations,
           why);
    return false;
  }

  // The iteration budget is spent.
  bool exhausted() const { return r_.iterations >= options_.max_iterations; }

  // The k-th point (k >= 1) of the van der Corput sequence in base b, in [0, 1).
  static double halton(int k, int b) {
    double f = 1.0, x = 0.0;
    for (int i = k; i > 0; i /= b) {
      f /= b;
      x += f * (i % b);
    }
    return x;
  }

 private:
  // --- Forward solves ---------------------------------------------------------------------

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
  enum class Mode { Step, Precise, Difference };
  bool evaluate(const VectorXd& T, const Point* from, Point& out, Mode mode = Mode::Step,
                const SolverOptions* options = nullptr) {
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

  bool loads_unloaded_part(const VectorXd& from, const VectorXd& to) const {
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
  double error_tolerance() const {
    return target_.rotation ? std::min(options_.position_tolerance, rotation_weight_ * options_.rotation_tolerance)
                            : options_.position_tolerance;
  }

  void error(Point& p) const {
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
  bool jacobian(Point& p) {
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

  // --- Phase 1: reach the target ----------------------------------------------------------

  // Levenberg-Marquardt with T >= 0: each step the non-negative least-squares problem
  // min |J d + e|^2 + lambda |d|^2; kept if the error drops; lambda by the gain ratio (Nielsen).
  // J by differences at the start, then Broyden's update along each kept step that halved the
  // error; differenced again after a slower step, where a step fails on the updated J, before a
  // claim of stationarity and once reached.
  // Reached, or why not (in `why`).
  Reach reach_target(Point& cur, std::string& why) {
    const std::vector<int> all = all_tendons(cur.T.size());
    double lambda = 1e-3 * std::max(cur.J.colwise().squaredNorm().maxCoeff(), std::numeric_limits<double>::min());
    double nu = 2.0;
    bool exact = true;  // cur.J is by differences at cur (not updated)
    std::vector<double> kept;  // the error after each kept step
    auto refresh = [&]() {
      if (!jacobian(cur)) {
        why = "the Jacobian by differences of forward solves could not be formed";
        return false;
      }
      exact = true;
      return true;
    };
    while (!cur.reached) {
      // Stationary for the distance: not even the undamped linear model gets closer.
      const double e2 = cur.e.squaredNorm();
      const VectorXd y0 = damped_step(cur.J, cur.e, cur.T, lambda_floor(cur.J), all);
      if ((cur.J * (y0 - cur.T) + cur.e).squaredNorm() >= e2 * (1.0 - 1e-12)) {
        if (!exact) {
          if (!refresh()) return Reach::Failed;
          continue;
        }
        why = "no step with non-negative tensions gets closer: the closest pose found (a local minimum of the distance)";
        return Reach::Stationary;
      }
      if (exhausted()) {
        why = "iteration limit before the target was reached";
        return Reach::Limit;
      }
      const VectorXd y = damped_step(cur.J, cur.e, cur.T, std::max(lambda, lambda_floor(cur.J)), all);
      const VectorXd d = y - cur.T;
      if (d.cwiseAbs().maxCoeff() <= 1e-14 * (cur.T.cwiseAbs().maxCoeff() + tension_scale_)) {
        if (!exact) {
          if (!refresh()) return Reach::Failed;
          continue;
        }
        why = "no step with non-negative tensions gets closer: the closest pose found (the steps vanish)";
        return Reach::Stationary;
      }
      const double predicted = e2 - (cur.J * d + cur.e).squaredNorm();
      ++r_.iterations;
      Point trial;
      if (evaluate(y, &cur, trial) && trial.merit() < cur.merit()) {
        const double rho = (e2 - trial.e.squaredNorm()) / std::max(predicted, std::numeric_limits<double>::min());
        // Broyden's update after a step that at least halved the error; a slower one differences J.
        const bool fast = trial.merit() <= 0.5 * cur.merit();
        trial.J = cur.J + (trial.e - cur.e - cur.J * d) * d.transpose() / d.squaredNorm();
        cur = std::move(trial);
        exact = false;
        if (!fast && !refresh()) return Reach::Failed;
        ++r_.accepted_steps;
        kept.push_back(cur.merit());
        if (!cur.reached && kept.size() > kStallSteps && cur.merit() > 0.5 * kept[kept.size() - 1 - kStallSteps]) {
          why = "the distance stopped falling (by less than half over " + std::to_string(kStallSteps) +
                " steps): the closest pose found";
          return Reach::Stalled;
        }
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * std::min(rho, 1.0) - 1.0, 3));
        nu = 2.0;
      } else if (!exact) {  // the updated J may be what failed: difference it before damping more
        if (!refresh()) return Reach::Failed;
      } else {
        lambda = std::max(lambda, lambda_floor(cur.J)) * nu;
        nu *= 2.0;
      }
    }
    return exact || refresh() ? Reach::Reached : Reach::Failed;
  }

  // --- Phase 2: least norm on the target ---------------------------------------------------

  // Gauss-Newton corrections over the free tendons from a trial point back onto the target (to
  // kRestoreFraction of the tolerance, or as close as they get within it): on the Jacobian of
  // the step's start (a chord method: the trial moved little), then, where a correction does not
  // halve the error, on the Jacobian at the last corrected point; at most kCorrections forward
  // solves. Then c's own Jacobian.
  bool restore(Point& c, const MatrixXd& J0, const std::vector<int>& free) {
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
  MatrixXd reduced_hessian(const Point& cur, const Structure& s) {
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
  void minimise_norm(Point& cur) {
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

  void finish(Point& p, InverseStatus status, std::string message) {
    r_.status = status;
    r_.message = std::move(message);
    r_.tensions.assign(p.T.data(), p.T.data() + p.T.size());
    r_.position_error = p.position_error;
    r_.rotation_error = p.rotation_error;
    if (status != InverseStatus::Converged) {
      r_.minimum_norm = false;
      r_.optimality = 0.0;
      r_.tension_resolution = 0.0;
    }
    r_.solution = std::move(p.solution);
  }

  const StaticModel& model_;
  ModelWorkspace& ws_;
  ModelInput input_;
  const InverseTarget& target_;
  const InverseOptions& options_;
  InverseResult& r_;
  SolverOptions warm_, cold_, tight_, tight_cold_, final_;
  Mat3 R_target_ = Mat3::Identity();
  double rotation_weight_ = 0.0;
  double tension_scale_ = 1.0;
  double input_start_max_ = 0.0;
  bool hessian_complete_ = true;
  std::string message_;
};

std::string component(const char* name, int i) { return std::string("target.") + name + "[" + std::to_string(i) + "]"; }

std::string matrix_text(const Mat3& R) {
  std::string s = "[";
  for (int i = 0; i < 3; ++i) {
    s += i ? ", [" : "[";
    for (int j = 0; j < 3; ++j) s += (j ? ", " : "") + format_value(R(i, j));
    s += "]";
  }
  return s + "]";
}

}  // namespace

void InverseTarget::validate() const {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(position[i]))
      throw InputError(component("position", i), format_value(position[i]), "must be a finite number (m)");
    if (rotation && !std::isfinite((*rotation)[i]))
      throw InputError(component("rotation", i), format_value((*rotation)[i]), "must be a finite number (rad)");
  }
  if (!std::isfinite(rotation_weight) || rotation_weight < 0.0)
    throw InputError("target.rotation_weight", format_value(rotation_weight),
                     "must be a finite number >= 0 (m per rad; 0: the robot's length)");
}

Vec3 InverseTarget::rotation_from_matrix(const Mat3& R) {
  if (!R.allFinite()) throw InputError("target.rotation", matrix_text(R), "must be a rotation matrix of finite numbers");
  const double err = lie::orthonormality_error(R);
  if (!(err <= kRotationMatrixTolerance))
    throw InputError("target.rotation", matrix_text(R),
                     "must be a rotation matrix: |R^T R - I| = " + format_value(err) + " exceeds " +
                         format_value(kRotationMatrixTolerance));
  if (R.determinant() <= 0.0)
    throw InputError("target.rotation", matrix_text(R),
                     "must be a rotation matrix: det R = " + format_value(R.determinant()) + " (a reflection), not +1");
  return lie::log_so3(R);
}

void InverseOptions::validate() const {
  if (max_iterations < 1)
    throw InputError("inverse.max_iterations", std::to_string(max_iterations), "must be at least 1");
  const std::pair<const char*, double> tolerances[] = {{"inverse.position_tolerance", position_tolerance},
                                                       {"inverse.rotation_tolerance", rotation_tolerance},
                                                       {"inverse.tension_tolerance", tension_tolerance}};
  for (const auto& [name, v] : tolerances)
    if (!std::isfinite(v) || v <= 0.0) throw InputError(name, format_value(v), "must be a positive finite number");
}

std::string to_string(InverseStatus s) {
  switch (s) {
    case InverseStatus::Converged: return "converged";
    case InverseStatus::Unreachable: return "unreachable";
    case InverseStatus::MaxIterations: return "max_iterations";
    case InverseStatus::ForwardFailed: return "forward_failed";
  }
  return "unknown";
}

std::string InverseResult::brief_report() const {
  double norm = 0.0;
  for (double t : tensions) norm += t * t;
  char buf[320];
  if (converged())
    std::snprintf(buf, sizeof buf,
                  "%s: |dp| = %.3g m, |drot| = %.3g rad, %d iterations, %d forward solves, |T| = %.6g N, "
                  "minimum norm %s (Newton step %.2g N)",
                  to_string(status).c_str(), position_error, rotation_error, iterations, forward_solves,
                  std::sqrt(norm), minimum_norm ? "verified" : "not verified", optimality);
  else
    std::snprintf(buf, sizeof buf, "%s: |dp| = %.3g m, |drot| = %.3g rad, %d iterations, %d forward solves, |T| = %.6g N",
                  to_string(status).c_str(), position_error, rotation_error, iterations, forward_solves,
                  std::sqrt(norm));
  return message.empty() ? std::string(buf) : std::string(buf) + " (" + message + ")";
}

InverseResult inverse_solve(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& start,
                            const InverseTarget& target, const SolverOptions& solver, const InverseOptions& options) {
  target.validate();
  options.validate();
  if (start.actuation.kind != Actuation::Kind::Tensions)
    throw InputError("actuation", "displacements", "the inverse solve varies the tensions: start from tension input");
  InverseResult r;
  Solver(model, workspace, start, target, solver, options, r).run();
  return r;
}

}  // namespace tdcr
