// The equations of motion of CCsub and PRB (lumped_dynamics.hpp, docs/dynamics.md), integrated
// by CVODE (BDF, dense Newton matrices from the model's structured Jacobian).
#include "lumped/lumped_dynamics.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "lumped/lumped_problem.hpp"
#include "physics/tendon_path.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr::detail {

namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Twists = Eigen::Matrix<double, 6, Eigen::Dynamic>;

// Step of the fourth-order differences of a subsegment's local pose in its unknowns (angles,
// rad): truncation ~h^4 = 1e-12 relative, rounding ~1e-16 / h = 1e-13.
constexpr double kTwistStep = 1e-3;
// Step (rad) of the velocity-product terms' differences along q' (bias accelerations).
constexpr double kBiasStep = 1e-3;
// PRB: inertia added to the bending-plane angle phi of a subsegment, as a fraction of m l^2 (its
// disk's mass, its length): that of turning the plane of a bend of sqrt(kPhiInertia) rad. phi has no inertia of its own where the subsegment is straight (a polar angle at
// zero bend): without it M is singular there. It only slows a plane's turning near straight.
constexpr double kPhiInertia = 1e-2;
// CVODE steps allowed per output step.
constexpr long kMaxStepsPerOutput = 20000;

// The spatial inertia about the base origin, ordering (omega, v_o), of a body with mass m,
// centre c and rotational inertia Ic about c (base frame).
Mat6 spatial_inertia(double m, const Vec3& c, const Mat3& Ic) {
  const Mat3 C = lie::hat(c);
  Mat6 I;
  I.topLeftCorner<3, 3>() = Ic + m * C.transpose() * C;
  I.topRightCorner<3, 3>() = m * C;
  I.bottomLeftCorner<3, 3>() = m * C.transpose();
  I.bottomRightCorner<3, 3>() = m * Mat3::Identity();
  return I;
}

// V x* h: the rate of a spatial momentum h carried along by the spatial velocity V.
Vec6 cross_force(const Vec6& V, const Vec6& h) {
  Vec6 r;
  const Vec3 w = V.head<3>(), v = V.tail<3>(), n = h.head<3>(), f = h.tail<3>();
  r.head<3>() = w.cross(n) + v.cross(f);
  r.tail<3>() = w.cross(f);
  return r;
}

class LumpedDynamics final : public DynamicsIntegrator {
 public:
  LumpedDynamics(const LumpedModel& model, const LumpedBody& body, const DynamicsSettings& settings, double dt,
                 const SolverOptions& solver);
  ~LumpedDynamics() override { free_cvode(); }

  void initialize(const Solution& at_rest, const ModelInput& input) override;
  SimulationStep advance(double t_next, const Timeline& timeline) override;
  Solution shape() const override;

  // (K, M) about x at rest under input: the natural frequencies (Hz).
  Eigen::VectorXd frequencies(const Eigen::VectorXd& x, const ModelInput& input);

 private:
  static int rhs_fn(sunrealtype t, N_Vector y, N_Vector yd, void* user);
  static int jac_fn(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user, N_Vector, N_Vector, N_Vector);
  static void on_error(int, const char*, const char*, char* msg, void* user) {
    static_cast<LumpedDynamics*>(user)->cvode_message_ = msg;
  }
  void free_cvode();
  void check(int flag, const char* what) const {
    if (flag < 0) throw std::runtime_error(std::string("lumped dynamics: ") + what + " failed (" + std::to_string(flag) + ")");
  }
  // The input at t (from the timeline once advance() has one), bound to the problem if it changed.
  void input_at(double t);
  // Frames and the twist columns (omega; v_o) of every unknown at q into `T`.
  // With `points`, the link midpoints go there (and the link Jacobians are not computed).
  void twists(const double* q, Twists& T, std::vector<Vec3>* points = nullptr);
  // Q = -S r at q (frames_ and T_ must be those of q); S's diagonal blocks kept in S_.
  bool generalized_force(const double* q);
  // M at q from T_ (frames_ of q); the composite inertias kept in IC_.
  void mass_matrix();
  // b: velocity-product forces minus drag, at (q, v).
  void bias(const double* q, const double* v);
  double potential_energy(const double* q);
  // PRB: m a of link l at q'' = 0 from bias()'s stencil of positions (step h along q').
  Vec3 link_force(int l, double h) const {
    const Vec3 acc = (-link_stencil_[0][l] + 16.0 * link_stencil_[2][l] - 30.0 * link_c_[l] +
                      16.0 * link_stencil_[3][l] - link_stencil_[1][l]) / (12.0 * h * h);
    return link_mass_[l] * acc;
  }
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

  // Bodies: disk k = 1..N with its mass and rotational inertia (disk frame, diagonal).
  std::vector<double> mass_, air_length_;
  std::vector<Vec3> inertia_;
  std::vector<double> length_;  // l_j, j = 1..N
  // PRB: the backbone of a subsegment as point masses at its four link midpoints (its joints
  // between two disks would have no inertia of their own otherwise): mass, world position and
  // the local Jacobian (base frame) of link i of subsegment j at index 4 j + i.
  static constexpr int kLinks = 4;
  bool links_ = false;
  std::vector<double> link_mass_;
  std::vector<Vec3> link_c_, link_stencil_[4];
  std::vector<Eigen::Matrix<double, 3, 5>> link_J_;

  // State and buffers, sized once.
  double t_ = 0.0;
  Eigen::VectorXd q_, v_;
  std::vector<Frame> frames_, frames_b_;
  std::vector<SubsegmentPose> poses_;
  Twists T_, Tp_, Tm_;
  Eigen::VectorXd r_, Q_, b_, rhs_, damp_;
  std::vector<Mat3> S_;  // per subsegment m x m (top-left) of S
  Eigen::MatrixXd M_, Jr_, K_;
  Eigen::LLT<Eigen::MatrixXd> llt_;
  std::vector<Mat6> IC_, Io_;
  std::vector<Vec6> V_, A_;
  Eigen::VectorXd qs_;

  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr, abstol_ = nullptr;
  void* cvode_ = nullptr;
  SUNMatrix A_mat_ = nullptr;
  SUNLinearSolver ls_ = nullptr;
  bool cvode_ready_ = false;
  std::string cvode_message_;
  long debug_rhs_ = 0;
};

LumpedDynamics::LumpedDynamics(const LumpedModel& model, const LumpedBody& body, const DynamicsSettings& settings,
                               double dt, const SolverOptions& solver)
    : model_(model), body_(body), settings_(settings), dt_(dt), m_(body.per_subsegment), N_(body.N), n_(m_ * N_) {
  settings.validate();
  const Robot& robot = model.robot();
  const double mu = robot.backbone.linear_mass();
  // Disks: their own mass, on the routing's disk list (segment by segment).
  mass_.assign(N_ + 1, 0.0);
  inertia_.assign(N_ + 1, Vec3::Zero());
  air_length_.assign(N_ + 1, 0.0);
  length_.assign(N_ + 2, 0.0);
  for (int j = 1; j <= N_; ++j) length_[j] = body.statics.length(j);
  double disk_mass_total = 0.0, hole_radius = 0.0;
  for (const RoutedTendon& t : body.statics.routing().tendons) hole_radius = std::max(hole_radius, physics::max_offset(t));
  int k = 1;
  for (const Segment& s : robot.segments)
    for (int d = 0; d < s.disks && k <= N_; ++d, ++k) {
      mass_[k] = s.disk_mass;
      disk_mass_total += s.disk_mass;
      // A thin disk out to the tendon holes (the robot gives no disk radius).
      const double r2 = hole_radius * hole_radius;
      inertia_[k] = s.disk_mass * Vec3(r2 / 4.0, r2 / 4.0, r2 / 2.0);
    }
  if (!(mu > 0.0) && !(disk_mass_total > 0.0))
    throw InputError("robot.backbone.density", format_value(robot.backbone.density),
                     "a moving robot needs mass: give robot.backbone.density (or mass_per_length) or the disks' "
                     "disk_mass");
  // The backbone: half of each subsegment at each of its disks (the half at the base disk does
  // not move), with the rotary inertia of the section and of the half-length about the disk.
  const double ro = robot.backbone.outer_radius, ri = robot.backbone.inner_radius;
  const double rg2 = 0.25 * (ro * ro + ri * ri);
  links_ = m_ == 5;
  link_mass_.assign(kLinks * (N_ + 1), 0.0);
  link_c_.assign(kLinks * (N_ + 1), Vec3::Zero());
  for (auto& st : link_stencil_) st.assign(kLinks * (N_ + 1), Vec3::Zero());
  link_J_.assign(kLinks * (N_ + 1), Eigen::Matrix<double, 3, 5>::Zero());
  const PrbParameters& prb = model.effects().prb;
  const double gsum = prb.gamma[0] + prb.gamma[1] + prb.gamma[2] + prb.gamma[3];
  for (int j = 1; j <= N_; ++j) {
    for (int side : {j - 1, j}) {
      if (side == 0) continue;
      const double h = 0.5 * length_[j], mh = mu * h;
      // The section's rotary inertia always; CCsub: the half-length's mass and its rotary inertia
      // about the disk too.
      inertia_[side] += Vec3(mh * rg2, mh * rg2, 2.0 * mh * rg2);
      if (!links_) {
        mass_[side] += mh;
        inertia_[side] += Vec3(mh * h * h / 3.0, mh * h * h / 3.0, 0.0);
      }
      air_length_[side] += h;
    }
    if (links_)
      for (int i = 0; i < kLinks; ++i) link_mass_[kLinks * j + i] = mu * length_[j] * prb.gamma[i] / gsum;
  }
  // Accuracy: the static solve's tip tolerance as an angle, CVODE's relative tolerance.
  const double L = body.length;
  const double tip_tol = solver.tip_tolerance > 0.0 ? solver.tip_tolerance : SolverOptions::kTipToleranceOverLength * L;
  rtol_ = std::max(solver.cvode_rtol, 1e-12);
  atol_q_ = tip_tol / L;
  atol_v_ = atol_q_ / std::max(dt_, 1e-6);

  problem_ = body.make_problem();
  frames_.resize(N_ + 1);
  frames_b_.resize(N_ + 1);
  poses_.resize(N_ + 1);
  T_.setZero(6, n_);
  Tp_.setZero(6, n_);
  Tm_.setZero(6, n_);
  r_.setZero(n_);
  Q_.setZero(n_);
  b_.setZero(n_);
  rhs_.setZero(n_);
  damp_.setZero(n_);
  q_.setZero(n_);
  v_.setZero(n_);
  qs_.setZero(n_);
  S_.assign(N_ + 1, Mat3::Zero());
  M_.setZero(n_, n_);
  Jr_.setZero(n_, n_);
  K_.setZero(n_, n_);
  llt_ = Eigen::LLT<Eigen::MatrixXd>(n_);
  IC_.assign(N_ + 2, Mat6::Zero());
  Io_.assign(N_ + 1, Mat6::Zero());
  V_.assign(N_ + 1, Vec6::Zero());
  A_.assign(N_ + 1, Vec6::Zero());
}

void LumpedDynamics::free_cvode() {
  if (cvode_) CVodeFree(&cvode_);
  if (ls_) SUNLinSolFree(ls_);
  if (A_mat_) SUNMatDestroy(A_mat_);
  if (y_) N_VDestroy(y_);
  if (abstol_) N_VDestroy(abstol_);
  if (ctx_) SUNContext_Free(&ctx_);
  cvode_ = nullptr, ls_ = nullptr, A_mat_ = nullptr, y_ = nullptr, abstol_ = nullptr, ctx_ = nullptr;
}

void LumpedDynamics::input_at(double t) {
  if (timeline_) timeline_->at(t, input_);
  if (bound_valid_ && input_.actuation.values == bound_.actuation.values && input_.loads.tip_force == bound_.loads.tip_force &&
      input_.loads.tip_moment == bound_.loads.tip_moment && input_.loads.gravity == bound_.loads.gravity)
    return;
  // A new input: binding resolves its loads (this allocates; between constant timeline entries
  // it happens once per entry).
  problem_->bind_all(input_);
  problem_->set_parameter(1.0);
  bound_ = input_;
  bound_valid_ = true;
}

void LumpedDynamics::twists(const double* q, Twists& T, std::vector<Vec3>* points) {
  body_.compute_frames(q, N_, frames_b_.data(), poses_.data());
  if (links_) {
    std::vector<Vec3>& c = points ? *points : link_c_;
    for (int j = 1; j <= N_; ++j)
      for (int i = 0; i < kLinks; ++i)
        c[kLinks * j + i] = frames_b_[j - 1].p + frames_b_[j - 1].R * poses_[j].aux[3 + i];
  }
  double xs[8];
  SubsegmentPose g[4];
  static constexpr double kOffset[4] = {2.0, 1.0, -1.0, -2.0};
  static constexpr double kWeight[4] = {-1.0 / 12.0, 8.0 / 12.0, -8.0 / 12.0, 1.0 / 12.0};
  for (int j = 1; j <= N_; ++j) {
    const double* xj = q + m_ * (j - 1);
    const Mat3& R0 = frames_b_[j - 1].R;
    const Vec3& pj = frames_b_[j].p;
    for (int i = 0; i < m_; ++i) {
      // Fourth-order central differences: the mass matrix is ill-conditioned (torsion against
      // bending), so its columns' noise must stay near rounding.
      std::copy(xj, xj + m_, xs);
      for (int k = 0; k < 4; ++k) {
        xs[i] = xj[i] + kOffset[k] * kTwistStep;
        body_.local(j, xs, g[k]);
      }
      Mat3 dR = Mat3::Zero();
      Vec3 dp = Vec3::Zero();
      for (int k = 0; k < 4; ++k) {
        dR += kWeight[k] * g[k].R;
        dp += kWeight[k] * g[k].p;
      }
      dR /= kTwistStep;
      dp /= kTwistStep;
      const Vec3 w_loc = lie::vee(dR * poses_[j].R.transpose());
      if (links_ && !points)
        for (int l = 0; l < kLinks; ++l) {
          Vec3 dc = Vec3::Zero();
          for (int k = 0; k < 4; ++k) dc += kWeight[k] * g[k].aux[3 + l];
          link_J_[kLinks * j + l].col(i) = R0 * dc / kTwistStep;
        }
      const Vec3 a = R0 * dp;
      const Vec3 w = R0 * w_loc;
      T.col(m_ * (j - 1) + i) << w, a - w.cross(pj);
    }
  }
}

bool LumpedDynamics::generalized_force(const double* q) {
  Eigen::Map<const Eigen::VectorXd> x(q, n_);
  if (!problem_->residual(x, r_)) return false;
  const double EI = body_.EI;
  for (int j = 1; j <= N_; ++j) {
    const double* rj = r_.data() + m_ * (j - 1);
    double* Qj = Q_.data() + m_ * (j - 1);
    const double c = EI / length_[j];
    Mat3& S = S_[j];
    if (m_ == 3) {
      // CCsub: r = B y with B = [e_x e_y z_j] (frame of disk j-1); y's spring part is
      // (b_x, b_y, (GJ/EI) eps), the gradient of the springs' energy times l/EI.
      const Vec3 z = poses_[j].R.col(2);
      Mat3 B = Mat3::Identity();
      B.col(2) = z;
      S = c * B.inverse();
      const Vec3 Qv = -(S * Eigen::Map<const Vec3>(rj));
      std::copy(Qv.data(), Qv.data() + 3, Qj);
    } else {
      // PRB: the joint, twist rows are spring gradients times l/EI; the bending-plane row is the
      // gradient component divided by the bend angle a (lumped_problem.hpp, set_damping).
      const double a = q[m_ * (j - 1)] + q[m_ * (j - 1) + 1] + q[m_ * (j - 1) + 2];
      for (int i = 0; i < m_; ++i) Qj[i] = -c * rj[i];
      Qj[3] *= a;
      S.setZero();
      S(0, 0) = a;  // the phi row's factor (over c), read by jac_fn
    }
  }
  return Q_.allFinite();
}

void LumpedDynamics::mass_matrix() {
  // Composite inertias from the tip: IC_j = sum of the disks k >= j.
  IC_[N_ + 1].setZero();
  for (int k = N_; k >= 1; --k) {
    const Frame& f = frames_b_[k];
    const Mat3 Ic = f.R * inertia_[k].asDiagonal() * f.R.transpose();
    Io_[k] = spatial_inertia(mass_[k], f.p, Ic);
    IC_[k] = IC_[k + 1] + Io_[k];
    // PRB: the links of subsegment k + 1 are rigid with disk k.
    if (links_ && k < N_)
      for (int i = 0; i < kLinks; ++i)
        IC_[k] += spatial_inertia(link_mass_[kLinks * (k + 1) + i], link_c_[kLinks * (k + 1) + i], Mat3::Zero());
  }
  // Block (a, b), a <= b: the bodies moving rigidly with both columns are the disks k >= b and
  // the links of subsegments > b; PRB: the links of b move with its columns through link_J_.
  for (int bj = 1; bj <= N_; ++bj) {
    Eigen::Matrix<double, 6, Eigen::Dynamic> U = IC_[bj] * T_.middleCols(m_ * (bj - 1), m_);
    if (links_)
      for (int i = 0; i < kLinks; ++i) {
        const int l = kLinks * bj + i;
        const Eigen::Matrix<double, 3, 5>& J = link_J_[l];
        for (int c = 0; c < m_; ++c) {
          U.col(c).head<3>() += link_mass_[l] * link_c_[l].cross(Vec3(J.col(c)));
          U.col(c).tail<3>() += link_mass_[l] * J.col(c);
        }
      }
    for (int aj = 1; aj <= bj; ++aj) {
      M_.block(m_ * (aj - 1), m_ * (bj - 1), m_, m_).noalias() = T_.middleCols(m_ * (aj - 1), m_).transpose() * U;
      if (aj != bj) M_.block(m_ * (bj - 1), m_ * (aj - 1), m_, m_) = M_.block(m_ * (aj - 1), m_ * (bj - 1), m_, m_).transpose();
    }
  }
  if (links_)
    for (int j = 1; j <= N_; ++j) {
      // The diagonal block's own links: U above holds their rigid part (twist T of b), which
      // for b's own columns is not their motion: replace it by J^T m J.
      for (int i = 0; i < kLinks; ++i) {
        const int l = kLinks * j + i;
        const Eigen::Matrix<double, 3, 5>& J = link_J_[l];
        const auto Tj = T_.middleCols(m_ * (j - 1), m_);
        Eigen::Matrix<double, 5, 5> rigid;
        for (int c = 0; c < m_; ++c)
          for (int r = 0; r < m_; ++r)
            rigid(r, c) = link_mass_[l] * (Tj.col(r).tail<3>() + Tj.col(r).head<3>().cross(link_c_[l])).dot(J.col(c));
        M_.block(m_ * (j - 1), m_ * (j - 1), m_, m_) += link_mass_[l] * J.transpose() * J - rigid;
      }
      M_(m_ * (j - 1) + 3, m_ * (j - 1) + 3) += kPhiInertia * mass_[j] * length_[j] * length_[j];
    }
}

void LumpedDynamics::bias(const double* q, const double* v) {
  Eigen::Map<const Eigen::VectorXd> qv(q, n_), vv(v, n_);
  const double vn = vv.norm();
  // The columns' rates T' = dT/dq q' by a central difference along q'.
  Vec6 Tdot_v_sum = Vec6::Zero();
  const bool moving = vn > 0.0;
  double h = 0.0;
  if (moving) {
    // Fourth order along q' (the same stencil as twists()); PRB: the links' positions too, for
    // their accelerations (second differences).
    h = kBiasStep / vn;
    qs_ = qv + 2.0 * h * vv;
    twists(qs_.data(), Tp_, &link_stencil_[0]);
    Tp_ *= -1.0 / 12.0;
    qs_ = qv - 2.0 * h * vv;
    twists(qs_.data(), Tm_, &link_stencil_[1]);
    Tp_ += (1.0 / 12.0) * Tm_;
    qs_ = qv + h * vv;
    twists(qs_.data(), Tm_, &link_stencil_[2]);
    Tp_ += (8.0 / 12.0) * Tm_;
    qs_ = qv - h * vv;
    twists(qs_.data(), Tm_, &link_stencil_[3]);
    Tp_ -= (8.0 / 12.0) * Tm_;
    Tp_ /= h;
    body_.compute_frames(q, N_, frames_b_.data(), poses_.data());  // back to q
  }
  // Spatial velocities and bias accelerations of the disks, from the base.
  Vec6 V = Vec6::Zero(), A = Vec6::Zero();
  for (int k = 1; k <= N_; ++k) {
    V.noalias() += T_.middleCols(m_ * (k - 1), m_) * vv.segment(m_ * (k - 1), m_);
    if (moving) A.noalias() += Tp_.middleCols(m_ * (k - 1), m_) * vv.segment(m_ * (k - 1), m_);
    V_[k] = V;
    A_[k] = A;
  }
  (void)Tdot_v_sum;
  // Forces of the disks (momentum rates at q'' = 0, minus drag), summed from the tip, and their
  // generalized forces.
  Vec6 F = Vec6::Zero();
  for (int k = N_; k >= 1; --k) {
    Vec6 f = Vec6::Zero();
    if (moving) f = Io_[k] * A_[k] + cross_force(V_[k], Io_[k] * V_[k]);
    if (settings_.air_drag > 0.0) {
      const Vec3& p = frames_b_[k].p;
      const Vec3 vel = V_[k].tail<3>() + V_[k].head<3>().cross(p);
      const Vec3 drag = -settings_.air_drag * air_length_[k] * vel.norm() * vel;
      f.head<3>() -= p.cross(drag);
      f.tail<3>() -= drag;
    }
    F += f;
    Eigen::Matrix<double, 5, 1> own = Eigen::Matrix<double, 5, 1>::Zero();
    if (links_ && moving) {
      // The links of subsegment k + 1 are rigid with disk k; those of k move through link_J_.
      for (int i = 0; i < kLinks && k < N_; ++i) {
        const int l = kLinks * (k + 1) + i;
        const Vec3 fl = link_force(l, h);
        F.head<3>() += link_c_[l].cross(fl);
        F.tail<3>() += fl;
      }
      for (int i = 0; i < kLinks; ++i) {
        const int l = kLinks * k + i;
        own += link_J_[l].transpose() * link_force(l, h);
      }
    }
    b_.segment(m_ * (k - 1), m_).noalias() = T_.middleCols(m_ * (k - 1), m_).transpose() * F;
    if (links_) b_.segment(m_ * (k - 1), m_) += own.head(m_);
  }
}

double LumpedDynamics::spring(int i, const double* q) const {
  const int j = i / m_ + 1, c = i % m_;
  const double EI = body_.EI, GJ = body_.GJ, l = length_[j];
  if (m_ == 3) return c == 2 ? GJ / l : EI / l;
  if (c == 4) return GJ / l;
  const auto& prb = model_.effects().prb;
  if (c < 3) return prb.k_theta[c] * EI / l;
  // phi: turning the plane of a bend a changes the curvature vector's direction at the rate a.
  const double a = q[m_ * (j - 1)] + q[m_ * (j - 1) + 1] + q[m_ * (j - 1) + 2];
  return prb.k_theta[1] * EI / l * a * a;
}

int LumpedDynamics::rhs_fn(sunrealtype t, N_Vector y, N_Vector yd, void* user) {
  auto& s = *static_cast<LumpedDynamics*>(user);
  ++s.debug_rhs_;
  const double* yv = N_VGetArrayPointer(y);
  double* d = N_VGetArrayPointer(yd);
  const int n = s.n_;
  const double* q = yv;
  const double* v = yv + n;
  s.input_at(t);
  s.twists(q, s.T_);
  if (!s.generalized_force(q)) {
    if (std::getenv("TDCR_DEBUG_CVODE")) std::fprintf(stderr, "Q failed: r %s\n", s.r_.allFinite() ? "finite" : "nonfinite");
    return 1;  // recoverable: CVODE retries a smaller step
  }
  s.mass_matrix();
  s.bias(q, v);
  Eigen::Map<const Eigen::VectorXd> vv(v, n);
  for (int i = 0; i < n; ++i) s.damp_[i] = s.settings_.bending_damping_time * s.spring(i, q);
  s.rhs_ = s.Q_ - s.damp_.cwiseProduct(vv) - s.b_;
  s.llt_.compute(s.M_);
  if (s.llt_.info() != Eigen::Success) {
    if (std::getenv("TDCR_DEBUG_CVODE")) std::fprintf(stderr, "LLT failed\n");
    return 1;
  }
  Eigen::Map<Eigen::VectorXd> dq(d, n), dv(d + n, n);
  dq = vv;
  dv = s.llt_.solve(s.rhs_);
  return dv.allFinite() ? 0 : 1;
}

int LumpedDynamics::jac_fn(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user, N_Vector tmp1,
                           N_Vector, N_Vector) {
  (void)fy;
  auto& s = *static_cast<LumpedDynamics*>(user);
  const int n = s.n_;
  const double* q = N_VGetArrayPointer(y);
  // Refresh every buffer at this y (rhs_fn's last call may have been elsewhere).
  if (rhs_fn(t, y, tmp1, user) != 0) return 1;
  Eigen::Map<const Eigen::VectorXd> x(q, n);
  if (!s.problem_->jacobian(x, s.r_, s.Jr_)) return 1;
  // dQ/dq ~ -S dr/dq (S's own derivative meets r, zero at every equilibrium); d(b)/d(q, q') and
  // dM/dq are left out: the Newton matrix of a modified Newton iteration.
  for (int j = 1; j <= s.N_; ++j) {
    const double c = s.body_.EI / s.length_[j];
    const int r0 = s.m_ * (j - 1);
    if (s.m_ == 3) {
      s.K_.middleRows(r0, 3).noalias() = s.S_[j] * s.Jr_.middleRows(r0, 3);
    } else {
      s.K_.middleRows(r0, 5) = c * s.Jr_.middleRows(r0, 5);
      s.K_.row(r0 + 3) *= s.S_[j](0, 0);
    }
  }
  Eigen::Map<Eigen::MatrixXd> Jm(SUNDenseMatrix_Data(J), 2 * n, 2 * n);
  Jm.setZero();
  Jm.topRightCorner(n, n).setIdentity();
  Jm.bottomLeftCorner(n, n) = -s.llt_.solve(s.K_);
  Jm.bottomRightCorner(n, n) = -s.llt_.solve(Eigen::MatrixXd(s.damp_.asDiagonal()));
  return Jm.allFinite() ? 0 : 1;
}

void LumpedDynamics::initialize(const Solution& at_rest, const ModelInput& input) {
  if (!at_rest.converged()) throw InputError("timeline[0]", "", "the static answer at t = 0 did not converge");
  if (at_rest.unknowns.size() != n_)
    throw InputError("unknowns", std::to_string(at_rest.unknowns.size()), "not a static answer of this model");
  timeline_ = nullptr;
  input_ = input;
  bound_valid_ = false;
  input_at(0.0);
  Eigen::VectorXd y0(2 * n_);
  y0.head(n_) = at_rest.unknowns;
  y0.tail(n_).setZero();
  // PRB's gauge references (the bending planes of straight subsegments) from the rest shape.
  Eigen::VectorXd ignored;
  problem_->warm_guess(at_rest, ignored);
  q_ = at_rest.unknowns;
  v_.setZero();
  t_ = 0.0;
  free_cvode();
  check(SUNContext_Create(nullptr, &ctx_), "SUNContext_Create");
  y_ = N_VNew_Serial(2 * n_, ctx_);
  abstol_ = N_VNew_Serial(2 * n_, ctx_);
  if (!y_ || !abstol_) throw std::runtime_error("lumped dynamics: N_VNew_Serial failed");
  std::copy(y0.data(), y0.data() + 2 * n_, N_VGetArrayPointer(y_));
  double* at = N_VGetArrayPointer(abstol_);
  for (int i = 0; i < n_; ++i) at[i] = atol_q_, at[n_ + i] = atol_v_;
  cvode_ = CVodeCreate(CV_BDF, ctx_);
  if (!cvode_) throw std::runtime_error("lumped dynamics: CVodeCreate failed");
  check(CVodeInit(cvode_, &rhs_fn, 0.0, y_), "CVodeInit");
  check(CVodeSetErrHandlerFn(cvode_, &on_error, this), "CVodeSetErrHandlerFn");
  check(CVodeSetUserData(cvode_, this), "CVodeSetUserData");
  check(CVodeSVtolerances(cvode_, rtol_, abstol_), "CVodeSVtolerances");
  // Per output step: a step that needs more has met a singularity (e.g. a CCsub subsegment bent
  // to 90 deg, where its twist law degenerates), not a hard stretch of motion.
  check(CVodeSetMaxNumSteps(cvode_, kMaxStepsPerOutput), "CVodeSetMaxNumSteps");
  A_mat_ = SUNDenseMatrix(2 * n_, 2 * n_, ctx_);
  ls_ = SUNLinSol_Dense(y_, A_mat_, ctx_);
  if (!A_mat_ || !ls_) throw std::runtime_error("lumped dynamics: dense matrix or solver creation failed");
  check(CVodeSetLinearSolver(cvode_, ls_, A_mat_), "CVodeSetLinearSolver");
  if (problem_->has_jacobian() && !std::getenv("TDCR_NO_JAC")) check(CVodeSetJacFn(cvode_, &jac_fn), "CVodeSetJacFn");
  cvode_ready_ = true;
}

SimulationStep LumpedDynamics::advance(double t_next, const Timeline& timeline) {
  if (!cvode_ready_) throw std::logic_error("lumped dynamics: advance() before initialize()");
  timeline_ = &timeline;
  const auto c0 = std::chrono::steady_clock::now();
  if (!chart_chosen_) choose_bending_planes(timeline);
  const auto c1 = std::chrono::steady_clock::now();
  SimulationStep step;
  long before = 0, after = 0;
  CVodeGetNumSteps(cvode_, &before);
  int flag = CV_SUCCESS;
  while (t_ < t_next) {
    // Stop at the timeline's entries: the input's slope jumps there, and CVODE restarts.
    double stop = t_next;
    for (const TimelineEntry& e : timeline.entries)
      if (e.t > t_ * (1.0 + 1e-14) + 1e-300 && e.t < stop) stop = e.t;
    check(CVodeSetStopTime(cvode_, stop), "CVodeSetStopTime");
    sunrealtype reached = t_;
    cvode_message_.clear();
    flag = CVode(cvode_, stop, y_, &reached, CV_NORMAL);
    if (flag < 0) {
      t_ = reached;
      break;
    }
    t_ = reached;
    if (stop < t_next && t_ >= stop) check(CVodeReInit(cvode_, t_, y_), "CVodeReInit");
    if (t_ >= stop) t_ = stop;
  }
  CVodeGetNumSteps(cvode_, &after);
  if (std::getenv("TDCR_DEBUG_CVODE")) {
    long nf = 0, nj = 0, nni = 0, ncf = 0, netf = 0, nsetup = 0;
    double h = 0;
    CVodeGetNumRhsEvals(cvode_, &nf);
    CVodeGetNumJacEvals(cvode_, &nj);
    CVodeGetNumNonlinSolvIters(cvode_, &nni);
    CVodeGetNumNonlinSolvConvFails(cvode_, &ncf);
    CVodeGetNumErrTestFails(cvode_, &netf);
    CVodeGetNumLinSolvSetups(cvode_, &nsetup);
    CVodeGetLastStep(cvode_, &h);
    long nfels = 0;
    CVodeGetNumLinRhsEvals(cvode_, &nfels);
    std::fprintf(stderr, "my rhs %ld nfeLS %ld; ", debug_rhs_, nfels);
    std::fprintf(stderr, "chart %g s, all %g s; ", std::chrono::duration<double>(c1 - c0).count(), std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count());
    std::fprintf(stderr, "t %g steps %ld rhs %ld jac %ld setups %ld nni %ld ncf %ld netf %ld h %g flag %d %s\n", t_, after, nf, nj, nsetup, nni, ncf, netf, h, flag, cvode_message_.c_str());
  }
  const double* yv = N_VGetArrayPointer(y_);
  q_ = Eigen::Map<const Eigen::VectorXd>(yv, n_);
  v_ = Eigen::Map<const Eigen::VectorXd>(yv + n_, n_);
  step.iterations = static_cast<int>(after - before);
  step.t = flag < 0 ? t_ : t_next;
  // CVODE's weighted local error of its last step (RMS norm; below 1 when accepted).
  N_Vector ele = N_VClone(y_), ewt = N_VClone(y_);
  if (ele && ewt && CVodeGetEstLocalErrors(cvode_, ele) == CV_SUCCESS && CVodeGetErrWeights(cvode_, ewt) == CV_SUCCESS)
    step.residual = N_VWrmsNorm(ele, ewt);
  if (ele) N_VDestroy(ele);
  if (ewt) N_VDestroy(ewt);
  step.status = flag < 0 ? TerminationType::IntegrationFailed : TerminationType::Converged;
  // Energies and the tip at the reached state.
  input_at(step.t);
  twists(q_.data(), T_);
  mass_matrix();
  step.kinetic_energy = 0.5 * v_.dot(M_ * v_);
  step.potential_energy = potential_energy(q_.data());
  step.tip = frames_b_[N_];
  if (flag < 0 && step.status != TerminationType::Converged && !cvode_message_.empty()) {
    // Kept for simulate()'s message through the step's status; the text goes to the log.
  }
  return step;
}

void LumpedDynamics::choose_bending_planes(const Timeline& timeline) {
  chart_chosen_ = true;
  if (m_ != 5) return;
  double* y = N_VGetArrayPointer(y_);
  std::vector<bool> open(N_ + 1, false);
  bool any = false;
  for (int j = 1; j <= N_; ++j) {
    const double* x = y + m_ * (j - 1);
    open[j] = std::abs(x[0]) + std::abs(x[1]) + std::abs(x[2]) < 1e-12;
    any = any || open[j];
  }
  if (!any) return;
  std::unique_ptr<ModelWorkspace> ws = model_.make_workspace();
  for (const TimelineEntry& e : timeline.entries) {
    const Solution s = solve(model_, *ws, e.input);
    if (!s.converged()) continue;
    for (int j = 1; j <= N_; ++j) {
      const double* x = s.unknowns.data() + m_ * (j - 1);
      if (open[j] && std::abs(x[0]) + std::abs(x[1]) + std::abs(x[2]) > 1e-9) {
        y[m_ * (j - 1) + 3] = x[3];
        open[j] = false;
      }
    }
  }
  Solution chart;
  chart.unknowns = Eigen::Map<const Eigen::VectorXd>(y, n_);
  Eigen::VectorXd ignored;
  problem_->warm_guess(chart, ignored);  // the gauge references follow
  check(CVodeReInit(cvode_, t_, y_), "CVodeReInit");
}

double LumpedDynamics::potential_energy(const double* q) {
  double U = 0.0;
  for (int i = 0; i < n_; ++i) {
    const int c = i % m_;
    if (m_ == 5 && c == 3) continue;  // phi: no spring of its own
    U += 0.5 * spring(i, q) * q[i] * q[i];
  }
  // Conservative loads: gravity on the lumped masses, the tip force, constant tendon tensions.
  const Loads& L = input_.loads;
  for (int k = 1; k <= N_; ++k) U -= mass_[k] * L.gravity.dot(frames_b_[k].p);
  if (links_)
    for (int l = kLinks; l < kLinks * (N_ + 1); ++l) U -= link_mass_[l] * L.gravity.dot(link_c_[l]);
  U -= L.tip_force.dot(frames_b_[N_].p);
  if (input_.actuation.kind == Actuation::Kind::Tensions && !input_.actuation.mixed()) {
    const TendonRouting& routing = body_.statics.routing();
    for (const RoutedTendon& t : routing.tendons) {
      const double T = input_.actuation.values[t.index];
      if (T == 0.0) continue;
      Vec3 prev = physics::hole_position(frames_b_[0], t, routing.disk_s[0]);
      for (int c = 1; c <= t.end_disk; ++c) {
        const Vec3 h = physics::hole_position(frames_b_[c], t, routing.disk_s[c]);
        U += T * (h - prev).norm();
        prev = h;
      }
    }
  }
  return U;
}

Solution LumpedDynamics::shape() const {
  Solution s;
  s.unknowns = q_;
  s.disk_frames = body_.disk_frames(q_);
  s.summary.termination = TerminationType::Converged;
  return s;
}

Eigen::VectorXd LumpedDynamics::frequencies(const Eigen::VectorXd& x, const ModelInput& input) {
  timeline_ = nullptr;
  input_ = input;
  bound_valid_ = false;
  input_at(0.0);
  twists(x.data(), T_);
  if (!generalized_force(x.data())) throw std::runtime_error("lumped dynamics: residual failed");
  mass_matrix();
  // K = -dQ/dq by central differences of Q (the model's Jacobian is a forward difference).
  Eigen::VectorXd xp = x, Q0(n_);
  for (int i = 0; i < n_; ++i) {
    const double h = 1e-6;
    xp[i] = x[i] + h;
    twists(xp.data(), T_);
    generalized_force(xp.data());
    Q0 = Q_;
    xp[i] = x[i] - h;
    twists(xp.data(), T_);
    generalized_force(xp.data());
    K_.col(i) = -(Q0 - Q_) / (2.0 * h);
    xp[i] = x[i];
  }
  twists(x.data(), T_);
  mass_matrix();
  // PRB: phi is no coordinate of a straight subsegment (a polar angle at zero bend): held fixed.
  std::vector<int> keep;
  for (int i = 0; i < n_; ++i)
    if (!(m_ == 5 && i % m_ == 3)) keep.push_back(i);
  const int nk = static_cast<int>(keep.size());
  Eigen::MatrixXd Ks(nk, nk), Mk(nk, nk);
  for (int a = 0; a < nk; ++a)
    for (int b = 0; b < nk; ++b) {
      Ks(a, b) = 0.5 * (K_(keep[a], keep[b]) + K_(keep[b], keep[a]));
      Mk(a, b) = M_(keep[a], keep[b]);
    }
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Ks, Mk);
  Eigen::VectorXd f = es.eigenvalues().cwiseMax(0.0).cwiseSqrt() / (2.0 * M_PI);
  std::sort(f.data(), f.data() + f.size());
  return f;
}

}  // namespace
std::unique_ptr<DynamicsIntegrator> make_lumped_dynamics(const LumpedModel& model, const LumpedBody& body,
                                                         const DynamicsSettings& settings, double dt,
                                                         const SolverOptions& solver) {
  return std::make_unique<LumpedDynamics>(model, body, settings, dt, solver);
}

Eigen::VectorXd lumped_natural_frequencies(const LumpedModel& model, const LumpedBody& body, const Eigen::VectorXd& x,
                                           const ModelInput& input) {
  LumpedDynamics d(model, body, DynamicsSettings{}, 1.0, SolverOptions{});
  return d.frequencies(x, input);
}

}  // namespace tdcr::detail

namespace tdcr {

std::unique_ptr<DynamicsIntegrator> LumpedModel::make_dynamics_integrator(const DynamicsSettings& settings, double dt,
                                                                          const SolverOptions& solver) const {
  return detail::make_lumped_dynamics(*this, body(), settings, dt, solver);
}

Eigen::VectorXd LumpedModel::natural_frequencies(const Eigen::VectorXd& x, const ModelInput& input) const {
  return detail::lumped_natural_frequencies(*this, body(), x, input);
}

}  // namespace tdcr
