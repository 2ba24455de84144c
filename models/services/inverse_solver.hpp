// Private to models/services: the inverse solve's iteration (tdcr/models/inverse_solve.hpp; the
// method is in inverse_solve.cpp's opening comment). One Solver runs one inverse solve; its parts
// are defined where their idea is: the public entry and the rounds of both phases in
// inverse_solve.cpp, forward solves and the Jacobian in inverse_forward.cpp, phase 1 in
// inverse_reach.cpp, phase 2 in inverse_minimise.cpp, the step's and the target set's linear
// algebra in inverse_linear_algebra.cpp.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tdcr/models/inverse_solve.hpp"

namespace tdcr::detail::inverse {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Function tolerance of the inner forward solves (at most): the tips of warm and cold solves then
// agree to 1e-12 m or better (the paper robot, every model, n = 5..20, E and E / 10; at 1e-10 they
// differ by up to 1e-10 m), three orders below the default position tolerance.
inline constexpr double kInnerFunctionTolerance = 1e-12;
// Function tolerance of the forward solves that difference the Jacobian and of phase 2's (where
// they converge, else kInnerFunctionTolerance): their tips agree to about 1e-15 m.
inline constexpr double kDifferenceFunctionTolerance = 1e-14;
// Tip scatter (m) below which two differences are not told apart (consistency of a column).
inline constexpr double kTipNoise = 1e-12;
// Relative rank threshold of a Jacobian (singular values below it times the largest are zero): a
// planar robot's out-of-plane row is zero to 1e-17, a near-singular pose's smallest singular
// value is 1e-5 of the largest.
inline constexpr double kRankThreshold = 1e-8;
// Central-difference increment of the Jacobian, relative to max(T_j, tension scale). Its
// truncation error, not the tips' noise, limits the reduced gradient where a target coordinate
// is barely controllable (a tip force across the bending plane of the paper robot: singular
// values 1.6e-2, 4.8e-5, 3.6e-6 m/N): there 1e-3 errs by 1e-5 N, 1e-4 by 1e-7 N. (The models'
// differential kinematics is no alternative: it costs 5 to 17 warm solves, as it also forms the
// tip compliance, and VCref's is accurate to only 5e-7 .. 2e-4 relative on the paper robot, its
// shooting Jacobian being a forward difference.)
inline constexpr double kDifferenceStep = 1e-4;
// Increment of the reduced Hessian's second differences along a tangent direction, relative to
// max(|T|, tension scale): truncation (delta / T_c)^2 ~ 1e-5 and the tips' noise times the
// multipliers over delta^2 both stay far below B's own scale (that of I).
inline constexpr double kHessianStep = 1e-2;
// Gauss-Newton corrections back onto the target after a step, and how close to it they bring the
// tip (times the tolerance): the merit's error term, second order in this, then stays below the
// gain of a step of the tensions' resolution.
inline constexpr int kCorrections = 8;
inline constexpr double kRestoreFraction = 1e-2;
// Eigenvalues of the reduced Hessian below this are not positive (its scale is that of I).
inline constexpr double kCurvatureFloor = 1e-6;
// Steps in a row kept although their gain is below the merit's noise.
inline constexpr int kUnseenSteps = 3;
// Restarts of phase 1 from the cold answer when the warm-started iteration met the target on an
// equilibrium that the loading path does not reach.
inline constexpr int kBranchRestarts = 2;
// Other starts of phase 1 where it ends at a local minimum of the distance, the Halton points
// they are chosen from, and the bases of that sequence (one per tendon, cycled).
inline constexpr int kRestarts = 8;
inline constexpr int kCandidates = 32;
// Kept steps of phase 1 over which the error must at least halve (else another start is tried):
// Gauss-Newton halves it at every step even at a singular root.
inline constexpr std::size_t kStallSteps = 10;
inline constexpr std::array<int, 12> kPrimes = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37};

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

// --- Linear algebra (inverse_linear_algebra.cpp) -------------------------------------------

// The damped step from T over the tendons in `free` (the others stay at their value):
// argmin |J (y - T) + e|^2 + lambda |y - T|^2 over y >= 0, by non-negative least squares.
VectorXd damped_step(const MatrixXd& J, const VectorXd& e, const VectorXd& T, double lambda,
                     const std::vector<int>& free, double beta = 0.0);

// Smallest damping: keeps the step problem strictly convex without biasing it.
double lambda_floor(const MatrixXd& J);

// The structure of the target set at T over the tendons in `free` (see Structure).
Structure structure(const MatrixXd& J, const VectorXd& T, const std::vector<int>& free);

// --- The iteration ------------------------------------------------------------------------

class Solver {
 public:
  Solver(const StaticModel& model, ModelWorkspace& ws, const ModelInput& start, const InverseTarget& target,
         const SolverOptions& solver, const InverseOptions& options, InverseResult& result);

  // Phase 1, phase 2 and the answer solved cold, started again where the loading path does not
  // reach the target's equilibrium; fills the result.
  void run();

 private:
  enum class Reach { Reached, Stationary, Stalled, Limit, Failed };
  // How evaluate() solves: its tolerance and warm start (see there).
  enum class Mode { Step, Precise, Difference };

  // --- Forward solves (inverse_forward.cpp) ---
  bool evaluate(const VectorXd& T, const Point* from, Point& out, Mode mode = Mode::Step,
                const SolverOptions* options = nullptr);
  bool loads_unloaded_part(const VectorXd& from, const VectorXd& to) const;
  double error_tolerance() const;
  void error(Point& p) const;
  bool jacobian(Point& p);

  // --- Phase 1: reach the target (inverse_reach.cpp) ---
  bool reach(Point& cur);
  Reach reach_target(Point& cur, std::string& why);
  // The iteration budget is spent.
  bool exhausted() const { return r_.iterations >= options_.max_iterations; }

  // --- Phase 2: least norm on the target (inverse_minimise.cpp) ---
  bool restore(Point& c, const MatrixXd& J0, const std::vector<int>& free);
  MatrixXd reduced_hessian(const Point& cur, const Structure& s);
  void minimise_norm(Point& cur);

  // The result from p (inverse_solve.cpp).
  void finish(Point& p, InverseStatus status, std::string message);

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

}  // namespace tdcr::detail::inverse
