// Private to models/lumped/: the integrator of the lumped models' equations of motion
// (lumped_dynamics.hpp says what it integrates). Its CVODE side is in lumped_dynamics.cpp, its
// mechanics (bodies, mass matrix, generalized and velocity forces) in lumped_dynamics_mechanics.cpp.
#pragma once

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>

#include "lumped/lumped_dynamics.hpp"
#include "lumped/lumped_problem.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr::detail {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Twists = Eigen::Matrix<double, 6, Eigen::Dynamic>;

// Step of the fourth-order differences of a subsegment's local pose in its unknowns (angles,
// rad): truncation ~h^4 = 1e-12 relative, rounding ~1e-16 / h = 1e-13.
constexpr double kTwistStep = 1e-3;
// Step (rad) of the velocity-product terms' forward differences along q' (bias accelerations):
// truncation ~1e-6 of those terms, rounding of the closed-form twists ~1e-16 / 1e-6 = 1e-10.
constexpr double kBiasStep = 1e-6;
// PRB: inertia added to the bending-plane angle phi of a subsegment, as a fraction of m l^2 (its
// disk's and its links' mass, its length): that of turning the plane of a bend of sqrt(kPhiInertia) rad. phi
// has no inertia of its own where the subsegment is straight (a polar angle at zero bend):
// without it M is singular there. It only slows a plane's turning near straight.
constexpr double kPhiInertia = 1e-2;
// The dynamics' tip tolerance over the robot's length where the scene gives no
// solver.tip_tolerance (lumped_dynamics.cpp, docs/dynamics.md "Accuracy").
constexpr double kDynamicsTipToleranceOverLength = 1e-4;
// PRB's chain Newton matrix at every step (lumped_dynamics.cpp, initialize()): K's diagonal
// blocks (the statics' structured differences, dearer than M's factors) are computed anew at
// every this many Jacobians (and after a Newton convergence failure). The paper robot's tension
// step (bench_dynamics): 1: 204 steps, 294 right-hand sides, 1 failure; 5: 205, 263, none; 10:
// 218, 304, 1; 20: 224, 330, 2.
constexpr long kChainStiffnessEvery = 5;
// CVODE steps allowed per output step.
constexpr long kMaxStepsPerOutput = 20000;

// The spatial inertia about the base origin, ordering (omega, v_o), of a body with mass m,
// centre c and rotational inertia Ic about c (base frame).
// ([c]^T [c] = |c|^2 I - c c^T, not the product: a right-hand side takes one per disk.)
inline Mat6 spatial_inertia(double m, const Vec3& c, const Mat3& Ic) {
  const Vec3 mc = m * c;
  const Mat3 C = lie::hat(mc);
  Mat6 I;
  I.topLeftCorner<3, 3>() = Ic - mc * c.transpose();
  I.topLeftCorner<3, 3>().diagonal().array() += mc.dot(c);
  I.topRightCorner<3, 3>() = C;
  I.bottomLeftCorner<3, 3>() = -C;
  I.bottomRightCorner<3, 3>() = m * Mat3::Identity();
  return I;
}

// I += spatial_inertia(m, c, 0): a point mass m at c.
inline void add_point_inertia(Mat6& I, double m, const Vec3& c) {
  const Vec3 mc = m * c;
  const Mat3 C = lie::hat(mc);
  I.topLeftCorner<3, 3>() -= mc * c.transpose();
  I.topLeftCorner<3, 3>().diagonal().array() += mc.dot(c);
  I.topRightCorner<3, 3>() += C;
  I.bottomLeftCorner<3, 3>() -= C;
  I.bottomRightCorner<3, 3>().diagonal().array() += m;
}

// V x* h: the rate of a spatial momentum h carried along by the spatial velocity V.
inline Vec6 cross_force(const Vec6& V, const Vec6& h) {
  Vec6 r;
  const Vec3 w = V.head<3>(), v = V.tail<3>(), n = h.head<3>(), f = h.tail<3>();
  r.head<3>() = w.cross(n) + v.cross(f);
  r.tail<3>() = w.cross(f);
  return r;
}

/// The DynamicsIntegrator of CCsub and PRB: CVODE BDF on (q, q'), buffers sized once.
class LumpedDynamics final : public DynamicsIntegrator {
 public:
  LumpedDynamics(const LumpedModel& model, const LumpedBody& body, const DynamicsSettings& settings, double dt,
                 const SolverOptions& solver);
  ~LumpedDynamics() override { free_cvode(); }

  void initialize(const Solution& at_rest, const ModelInput& input) override;
  SimulationStep advance(double t_next, const Timeline& timeline) override;
  Solution shape() const override;
  double potential_energy() override;
  // Displacement input: every displacement-driven tendon must be elastic (lumped_dynamics.cpp).
  bool takes_displacement_input() const override { return true; }
  void check_displacement_input(const Timeline& timeline) const override;

  // (K, M) about x at rest under input: the natural frequencies (Hz).
  Eigen::VectorXd frequencies(const Eigen::VectorXd& x, const ModelInput& input);

 private:
  static int rhs_fn(sunrealtype t, N_Vector y, N_Vector yd, void* user);
  static int jac_fn(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user, N_Vector, N_Vector, N_Vector);
  static void on_error(int, const char*, const char*, char* msg, void* user) {
    static_cast<LumpedDynamics*>(user)->cvode_message_ = msg;
  }
  static int root_fn(sunrealtype t, N_Vector y, sunrealtype* g, void* user);
  void free_cvode();
  void check(int flag, const char* what) const {
    if (flag < 0) throw std::runtime_error(std::string("lumped dynamics: ") + what + " failed (" + std::to_string(flag) + ")");
  }
  // The input at t (from the timeline once advance() has one), bound to the problem if it changed.
  void input_at(double t);
  // Frames and the twist columns (omega; v_o) of every unknown at q into `T`.
  // With `points`, the link midpoints go there and the link Jacobians to link_J_step_.
  void twists(const double* q, Twists& T, std::vector<Vec3>* points = nullptr);
  // bias()'s twists at q (= its q + h v): the frames, the poses, the links' points (into
  // link_stencil_[3]) and, per subsegment j, only the products T_j v_j (tv_step_) and J_l v_j
  // (ljv_step_), which is all the velocity terms' forward difference takes.
  void twists_along(const double* q, const double* v);
  std::vector<Vec6> tv_step_;
  std::vector<Vec3> ljv_step_;
  // Q = -S r at q (frames_ and T_ must be those of q); S's diagonal blocks kept in S_.
  bool generalized_force(const double* q);
  // M at q from T_ (frames_ of q); the composite inertias kept in IC_.
  void mass_matrix();
  // The disks' spatial inertias Io_ at frames_b_ (mass_matrix() computes them too), PRB's rigid
  // links (link_rigid()) with them.
  void body_inertias();
  // q'' = M^-1 rhs_ by the articulated-body algorithm, O(N) (no M, no Cholesky), from T_, Io_,
  // PRB's links, and bias()'s V_, A_, pbody_ and link stencils.
  void articulated(Eigen::Map<Eigen::VectorXd>& qdd);
  template <int m>
  void articulated_m(Eigen::Map<Eigen::VectorXd>& qdd);
  std::vector<Vec6> pbody_;
  double bias_h_ = 0.0;          // bias()'s step along q' (0: at rest)
  template <int m>
  struct AbaStore {
    std::vector<Eigen::Matrix<double, 6, m>> U;
    std::vector<Eigen::Matrix<double, m, m>> Dinv;
    std::vector<Eigen::Matrix<double, m, 1>> u;
    void size(int N) {
      U.assign(N + 1, Eigen::Matrix<double, 6, m>::Zero());
      Dinv.assign(N + 1, Eigen::Matrix<double, m, m>::Zero());
      u.assign(N + 1, Eigen::Matrix<double, m, 1>::Zero());
    }
  };
  AbaStore<3> aba3_;
  AbaStore<5> aba5_;
  template <int m>
  AbaStore<m>& aba_store() {
    if constexpr (m == 3)
      return aba3_;
    else
      return aba5_;
  }
  template <int m>
  void mass_blocks();  // mass_matrix()'s blocks, m unknowns per subsegment
  // The velocity terms at (q, v): the disks' velocities V_ and accelerations at q'' = 0 A_, their
  // wrenches pbody_ (velocity products minus drag), the links' accelerations (PRB:
  // link_stencil_[2]; their positions at q + h q' in [3]).
  void bias(const double* q, const double* v);
  // At the q of the last twists_along() (frames_b_, the links' points in link_stencil_[3]).
  double potential_energy(const double* q);
  // v^T M v / 2 at (q, v), without M (twists_along(q, v): the frames and link points at q after).
  double kinetic_energy(const double* q, const double* v);
  // PRB: the mass of kPhiInertia's m l^2 for subsegment j.
  double phi_mass(int j) const;
  // PRB: m a of link l at q'' = 0 (bias() keeps the accelerations in link_stencil_[2]).
  Vec3 link_force(int l) const { return link_mass_[l] * link_stencil_[2][l]; }
  // PRB: the bending plane phi of a subsegment that is straight at rest is no state (a polar
  // angle at zero bend) but decides the plane it can start bending in: take it from the first
  // static answer along the timeline that bends the subsegment (planar motions start right).
  void choose_bending_planes(const Timeline& timeline);
  bool chart_chosen_ = false;
  // Springs' stiffness of unknown i (the diagonal of D / tau_bt) at q.
  double spring(int i, const double* q) const;

  const LumpedModel& model_;
  const LumpedBody& body_;
  DynamicsSettings settings_;
  double dt_;
  int m_, N_, n_;
  double rtol_, atol_q_, atol_v_;
  std::unique_ptr<LumpedProblem> problem_;
  const Timeline* timeline_ = nullptr;
  ModelInput input_, bound_;
  bool bound_valid_ = false;

  // Displacement input (elastic tendons; docs/dynamics.md, "Displacement input"): the tendons
  // driven by displacement pull with T_k = (EA_k / L_k) max(0, delta_k(t) - d_k(q)), a function
  // of the state; the problem is bound with them acting (tension_form_: placeholders) and their
  // tensions set per right-hand side. Sized once (set_up_displacement_input()).
  void set_up_displacement_input(const ModelInput& input);
  // T_k(q, t) of the driven tendons at the input_ of input_at(t), set on the problem (with the
  // backbone's compression under them: a fixed point, iterated); gap_ = delta - d. False if not finite.
  bool driven_tensions(const double* q);
  // The taut tendons' stiffness in the Newton matrix's K_ (jac_fn, after K_ and r_ at q).
  bool tendon_stiffness(const double* q);
  // The tendons' part of the potential energy under displacement input (lumped_dynamics.cpp).
  double tendon_energy() const;
  Eigen::VectorXd pull_base_, pert_T_, r_pert_, u_;
  Eigen::MatrixXd dd_;  // dd_k/dq, driven tendons x n
  bool displacement_ = false;
  std::vector<int> driven_;          // global tendon indices
  std::vector<double> ea_over_l_;    // EA_k / L_k (N/m), L_k the statics' free length
  Eigen::VectorXd driven_T_, gap_;
  std::vector<Frame> pull_frames_;
  ModelInput tension_form_;
  std::vector<double> placeholder_;
  std::vector<int> root_dir_;        // CVodeGetRootInfo's
  std::vector<char> taut_;           // per driven tendon: its mode for the root function (band)

  // Bodies: disk k = 1..N with its mass and rotational inertia (disk frame, diagonal).
  std::vector<double> mass_, air_length_;
  std::vector<Vec3> inertia_;
  std::vector<double> length_;  // l_j, j = 1..N
  // PRB: the backbone of a subsegment as point masses at its four link midpoints (its joints
  // between two disks would have no inertia of their own otherwise): mass, world position and
  // the local Jacobian (base frame) of link i of subsegment j at index 4 j + i.
  static constexpr int kLinks = 4;
  bool links_ = false;
  // The body has closed-form rates of its subsegments' poses (LumpedBody::local_rates); else
  // the twists are fourth-order differences of local().
  bool rates_ = false;
  // The unknowns that move link i of a subsegment (LumpedBody::link_unknowns: PRB's links 1..3
  // by 2, 3 and 4 of them), ascending; a link none moves (PRB's first) is rigid with the subsegment's
  // base disk and its mass is part of that disk's spatial inertia in Io_ (body_inertias()).
  int link_cols_[kLinks][5] = {};
  int link_ncols_[kLinks] = {};
  bool link_rigid(int i) const { return link_ncols_[i] == 0; }
  std::vector<double> link_mass_;
  std::vector<Vec3> link_c_, link_stencil_[4];
  std::vector<Eigen::Matrix<double, 3, 5>> link_J_, link_J_step_;  // at q, at bias()'s q + h q'
  // PRB: the four links' part of joint k's factors in articulated_m() (added to IA T_k, to
  // T_k^T IA T_k with the phi inertia, and to the articulated inertia passed on), at the q of the
  // last right-hand side: chain_factor() takes them from there.
  std::vector<Eigen::Matrix<double, 6, 5>> link_U_;
  std::vector<Eigen::Matrix<double, 5, 5>> link_D_;
  std::vector<Mat6> link_I_;

  // State and buffers, sized once.
  double t_ = 0.0;
  Eigen::VectorXd q_, v_;
  std::vector<Frame> frames_, frames_b_;
  std::vector<SubsegmentPose> poses_;
  std::vector<Frame> frames_q_;           // bias(): the frames and poses at q while it
  std::vector<SubsegmentPose> poses_q_;   // evaluates the twists at q + h q'

  Twists T_, Tp_;
  Eigen::VectorXd r_, Q_, rhs_, damp_;
  Eigen::VectorXd damp_const_;  // tau_bt K of the constant springs (PRB's phi rows: recomputed)
  std::vector<Mat3> S_;  // per subsegment m x m (top-left) of S
  Eigen::MatrixXd M_, Jr_, K_;
  // M_, Jr_, K_ and the dense Newton solver's n x n buffers, sized at first use (the dense
  // Newton systems of displacement input, the frequencies): the chain form needs none of them.
  void size_dense();
  // The Newton systems (I - gamma J) x = b by their Schur complement (lumped_dynamics.cpp,
  // make_schur_solver): n x n instead of 2n x 2n, since J's first block row is [0 I].
  Eigen::MatrixXd schur_, schur_A21_, schur_M_;
  Eigen::PartialPivLU<Eigen::MatrixXd> schur_lu_;
  Eigen::VectorXd schur_b_;
  double schur_gamma_ = 0.0;
  SUNLinearSolver make_schur_solver();
  // The (t, y) of the last successful right-hand side: the buffers (M_, S_, r_, damp_, the
  // problem's residual state) are those of that point.
  bool last_valid_ = false;
  double last_t_ = 0.0;
  Eigen::VectorXd last_y_;
  // CVODE's Newton matrix (lumped_dynamics.cpp, make_newton_matrix): J's blocks M, K, D and
  // CVODE's gamma, not the dense 2n x 2n matrix.
  // Dense (displacement input): M, K, D. Chain (chain_): what the articulated-body
  // factorisation of M + gamma D + gamma^2 K needs at the Jacobian's q: the twists, the disks'
  // spatial inertias, the links' parts of the factorisation (link_U_...), D and K's diagonal
  // blocks Kd (m x n), no n x n matrix.
  struct NewtonMatrix {
    const LumpedDynamics* owner = nullptr;
    Eigen::MatrixXd M, K;
    Eigen::VectorXd D;
    Twists T;
    Eigen::MatrixXd Kd;
    std::vector<Mat6> Io;
    std::vector<Eigen::Matrix<double, 6, 5>> link_U;
    std::vector<Eigen::Matrix<double, 5, 5>> link_D;
    std::vector<Mat6> link_I;
    double gamma = 0.0;
    bool scaled = false;
  };
  static SUNMatrix make_newton_matrix(SUNContext ctx, const LumpedDynamics* owner);
  // The chain Newton solver (tension and load input, both models): CVODE's systems with M exact
  // and K by its diagonal blocks (the springs and the subsegments' own load terms; the coupling
  // of a subsegment's law to the distal shape left out), solved by the articulated-body
  // algorithm in O(N) (lumped_dynamics.cpp, make_schur_solver). Displacement input keeps the
  // dense n x n LU: its tendons' stiffness couples every subsegment and dominates the bending.
  bool chain_ = false;
  Eigen::MatrixXd Kd_;           // m x n: K's diagonal blocks (jac_fn)
  long kd_age_ = -1, kd_fails_ = 0;  // Jacobians since Kd_ was computed; CVODE's failures then
  Eigen::VectorXd chain_b_;      // n
  const NewtonMatrix* chain_nm_ = nullptr;  // the matrix of the last setup
  template <int m>
  struct ChainFactors {
    std::vector<Eigen::Matrix<double, 6, m>> UL, UR;  // IA T_k, IA^T T_k (IA not symmetric: K's blocks)
    std::vector<Eigen::Matrix<double, m, m>> Dinv;
    std::vector<Eigen::Matrix<double, m, 1>> u;
    void size(int N) {
      UL.assign(N + 1, Eigen::Matrix<double, 6, m>::Zero());
      UR = UL;
      Dinv.assign(N + 1, Eigen::Matrix<double, m, m>::Zero());
      u.assign(N + 1, Eigen::Matrix<double, m, 1>::Zero());
    }
  };
  ChainFactors<3> chain3_;
  ChainFactors<5> chain5_;
  template <int m>
  ChainFactors<m>& chain_store() {
    if constexpr (m == 3)
      return chain3_;
    else
      return chain5_;
  }
  // Factor M + gamma D + gamma^2 blockdiag(Kd) of `nm` (false: singular or not finite).
  template <int m>
  bool chain_factor(const NewtonMatrix& nm, double gamma);
  // chain_b_ <- z with (M + gamma D + gamma^2 blockdiag(Kd)) z = D b2 + Kd (b1 + gamma b2), b =
  // (b1, b2) CVODE's right-hand side (2n), with the last chain_factor().
  template <int m>
  void chain_solve(const double* b, double gamma);
  std::vector<Mat6> IC_, Io_;
  std::vector<Vec6> V_, A_;
  Eigen::VectorXd qs_;

  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr, abstol_ = nullptr;
  N_Vector ele_ = nullptr, ewt_ = nullptr;  // advance(): CVODE's local errors and their weights
  void* cvode_ = nullptr;
  SUNMatrix A_mat_ = nullptr;
  SUNLinearSolver ls_ = nullptr;
  bool cvode_ready_ = false;
  std::string cvode_message_;
};

}  // namespace tdcr::detail
