#include "tdcr/models/prb.hpp"

#include <chrono>
#include <cmath>
#include <string>

#include "common/load_continuation.hpp"
#include "common/model_factories.hpp"
#include "common/newton_summary.hpp"
#include "common/subsegment_statics.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

namespace {
constexpr int kU = 5;  // unknowns per subsegment
// The phi gauge (see prb.hpp): eta a0^2 / (a0^2 + t^2) sin(phi - phi_0), t = (l/EI) |M*|.
// It pins phi where the in-plane moment vanishes (t << a0) and fades out as soon as the moment
// defines the plane: below 1e-12 (a hundredth of the default tolerance) for t >= 1e-3.
constexpr double kGaugeEta = 1e-6;
constexpr double kGaugeA0 = 1e-6;
// Unknown scale of phi: finite-difference step 1.5e-4 rad for phi, so that the phi column of the
// Jacobian resolves the gauge term above the rounding noise of the residual (~1e-16 / step).
constexpr double kPhiScale = 1e-4;
// Maximum scaled Newton step (rad of joint angle), see solve().
constexpr double kMaxNewtonStep = 1.0;
}  // namespace

/// Geometry of one PRB subsegment in the frame of its base disk.
struct PrbLocal {
  Vec3 joint[3];  // joint centres P_1..P_3
  Vec3 mid[4];    // link midpoints
  Vec3 end;       // O_j
  Mat3 R;         // rotation of disk j relative to disk j-1
};

struct PrbModel::Impl {
  detail::SubsegmentStatics statics;
  double EI = 0.0, GJ = 0.0;
  double gamma[4] = {};
  double gamma_sum = 1.0;
  double k_theta[3] = {};
  int N = 0, J = 0;

  explicit Impl(const Scene& scene) : statics(scene) {
    const BackboneStiffness k = scene.robot.backbone.effective_stiffness();
    EI = k.EI;
    GJ = k.GJ;
    gamma_sum = 0.0;
    for (int i = 0; i < 4; ++i) {
      gamma[i] = scene.effects.prb.gamma[i];
      gamma_sum += gamma[i];
    }
    for (int q = 0; q < 3; ++q) k_theta[q] = scene.effects.prb.k_theta[q];
    N = statics.subsegments();
    J = statics.active_subsegments();
  }

  // Eq. 11-12 with the twist: the rigid-link body of subsegment j in its base disk frame.
  void local(int j, const double* xj, PrbLocal& g) const {
    const double l = statics.length(j);
    const double cp = std::cos(xj[3]), sp = std::sin(xj[3]);
    // In-plane coordinates (x', z') of the chain, then x' mapped along (cos phi, sin phi).
    double x = 0.0, z = gamma[0] * l, a = 0.0;
    auto to3 = [&](double px, double pz) { return Vec3(px * cp, px * sp, pz); };
    g.mid[0] = Vec3(0.0, 0.0, 0.5 * gamma[0] * l);
    for (int q = 0; q < 3; ++q) {
      g.joint[q] = to3(x, z);
      a += xj[q];
      const double L = gamma[q + 1] * l, sa = std::sin(a), ca = std::cos(a);
      g.mid[q + 1] = to3(x + 0.5 * L * sa, z + 0.5 * L * ca);
      x += L * sa;
      z += L * ca;
    }
    g.end = to3(x, z);
    // Rz(phi) Ry(a) Rz(eps - phi).
    const double sa = std::sin(a), ca = std::cos(a);
    const double e = xj[4] - xj[3], ce = std::cos(e), se = std::sin(e);
    Mat3 A;  // Rz(phi) Ry(a)
    A << cp * ca, -sp, cp * sa,
         sp * ca, cp, sp * sa,
         -sa, 0.0, ca;
    g.R.col(0) = ce * A.col(0) + se * A.col(1);
    g.R.col(1) = -se * A.col(0) + ce * A.col(1);
    g.R.col(2) = A.col(2);
  }

  // Frames of all disks; locals[j] (if given) receives the local geometry of subsegments 1..J;
  // centroids (if given) the backbone centre of mass of every subsegment (base frame).
  void compute_frames(const double* x, Frame* frames, PrbLocal* locals, Vec3* centroids) const {
    frames[0] = Frame{};
    PrbLocal g;
    for (int j = 1; j <= N; ++j) {
      const double l = statics.length(j);
      const Frame& prev = frames[j - 1];
      Frame& f = frames[j];
      if (j > J) {
        f.R = prev.R;
        f.p = prev.p + l * prev.R.col(2);
        if (centroids) centroids[j] = prev.p + 0.5 * l * prev.R.col(2);
        continue;
      }
      PrbLocal& gl = locals ? locals[j] : g;
      local(j, x + kU * (j - 1), gl);
      f.R = prev.R * gl.R;
      f.p = prev.p + prev.R * gl.end;
      if (centroids) {
        Vec3 c = Vec3::Zero();
        for (int i = 0; i < 4; ++i) c += gamma[i] * gl.mid[i];
        centroids[j] = prev.p + prev.R * (c / gamma_sum);
      }
    }
  }
};

namespace {

class PrbWorkspace final : public LegacyWorkspace {
 public:
  bvp::NewtonSolver newton;
  std::vector<Frame> frames;
  std::vector<PrbLocal> locals;
  std::vector<Vec3> centroids, F, M;
  std::vector<double> phi_ref;
};

// Its parameter is the load factor (continuation): the distal wrenches are linear in the loads.
class PrbSystem final : public bvp::ParameterizedSystem {
 public:
  PrbSystem(const PrbModel::Impl& m, PrbWorkspace& ws) : m_(m), ws_(ws) {
    ws_.frames.resize(m.N + 1);
    ws_.locals.resize(m.N + 1);
    ws_.centroids.assign(m.N + 1, Vec3::Zero());
    ws_.F.assign(m.N + 1, Vec3::Zero());
    ws_.M.assign(m.N + 1, Vec3::Zero());
    ws_.phi_ref.assign(m.N + 1, 0.0);
  }
  int size() const override { return kU * m_.J; }
  void set_parameter(double lambda) override { load_ = lambda; }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override {
    s.setOnes();
    for (int j = 0; j < m_.J; ++j) s[kU * j + 3] = kPhiScale;
  }

  // Moment about O_{j-1} (base frame) of everything distal of disk j-1, for the current state.
  Vec3 base_moment(int j) const {
    const Frame& a = ws_.frames[j - 1];
    Vec3 Mb = ws_.M[j] + (ws_.frames[j].p - a.p).cross(ws_.F[j]);
    if (m_.statics.has_backbone_weight()) Mb += (ws_.centroids[j] - a.p).cross(m_.statics.backbone_weight(j));
    return Mb;
  }

  // Evaluate frames and distal wrenches at x.
  void evaluate(const double* x) {
    Frame* fr = ws_.frames.data();
    m_.compute_frames(x, fr, ws_.locals.data(), ws_.centroids.data());
    m_.statics.distal_wrenches(fr, ws_.centroids.data(), ws_.F.data(), ws_.M.data());
  }

  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    evaluate(x.data());
    const bool bb = m_.statics.has_backbone_weight();
    const double gj_ei = m_.GJ / m_.EI;
    for (int j = 1; j <= m_.J; ++j) {
      const Frame& a = ws_.frames[j - 1];
      const PrbLocal& g = ws_.locals[j];
      const double* xj = x.data() + kU * (j - 1);
      double* fj = f.data() + kU * (j - 1);
      const double s = m_.statics.length(j) / m_.EI;
      const double cp = std::cos(xj[3]), sp = std::sin(xj[3]);
      // Distal wrench in the frame of disk j-1 (only relative geometry from here on).
      const Vec3 F = load_ * (a.R.transpose() * ws_.F[j]);
      const Vec3 Mj = load_ * (a.R.transpose() * ws_.M[j]);  // about O_j
      Vec3 W = Vec3::Zero();
      if (bb) W = (load_ / m_.gamma_sum) * (a.R.transpose() * m_.statics.backbone_weight(j));
      const Vec3 y(-sp, cp, 0.0);
      // Eq. 48-51: joint q balances the moment of everything distal of it.
      for (int q = 0; q < 3; ++q) {
        Vec3 Mq = Mj + (g.end - g.joint[q]).cross(F);
        if (bb)
          for (int i = q + 1; i < 4; ++i) Mq += (g.mid[i] - g.joint[q]).cross(m_.gamma[i] * W);
        fj[q] = m_.k_theta[q] * xj[q] - s * y.dot(Mq);
      }
      // Moment about O_{j-1}.
      Vec3 Mb = Mj + g.end.cross(F);
      if (bb)
        for (int i = 0; i < 4; ++i) Mb += g.mid[i].cross(m_.gamma[i] * W);
      // Eq. 52-53, two-sided: the in-plane moment has no component across the joint axis.
      const double t2 = s * s * (Mb.x() * Mb.x() + Mb.y() * Mb.y());
      const double gauge = kGaugeEta * kGaugeA0 * kGaugeA0 / (kGaugeA0 * kGaugeA0 + t2);
      fj[3] = s * (cp * Mb.x() + sp * Mb.y()) + gauge * std::sin(xj[3] - ws_.phi_ref[j]);
      // Eq. 54: twist about the end tangent.
      fj[4] = gj_ei * xj[4] - s * g.R.col(2).dot(Mb);
    }
    return f.allFinite();
  }

 private:
  const PrbModel::Impl& m_;
  PrbWorkspace& ws_;
  double load_ = 1.0;
};

}  // namespace

PrbModel::PrbModel(const Scene& scene) : scene_(scene) {
  scene_.validate();
  if (scene_.actuation.kind != Actuation::Kind::Tensions)
    throw InputError("actuation.kind", "displacements", "the PRB model is driven by tendon tensions");
  for (int i = 0; i < 4; ++i) {
    const double g = scene_.effects.prb.gamma[i];
    if (!(g > 0.0) || !std::isfinite(g))
      throw InputError("effects.prb.gamma[" + std::to_string(i) + "]", format_value(g), "must be positive and finite");
  }
  for (int q = 0; q < 3; ++q) {
    const double k = scene_.effects.prb.k_theta[q];
    if (!(k > 0.0) || !std::isfinite(k))
      throw InputError("effects.prb.k_theta[" + std::to_string(q) + "]", format_value(k),
                       "must be positive and finite");
  }
  impl_ = std::make_unique<Impl>(scene_);
}

PrbModel::~PrbModel() = default;

std::unique_ptr<LegacyWorkspace> PrbModel::make_workspace() const { return std::make_unique<PrbWorkspace>(); }

std::vector<Frame> PrbModel::frames(const Eigen::VectorXd& x) const {
  if (x.size() != kU * impl_->N)
    throw InputError("unknowns", std::to_string(x.size()), "expected 5 unknowns per subsegment");
  std::vector<Frame> f(impl_->N + 1);
  impl_->compute_frames(x.data(), f.data(), nullptr, nullptr);
  return f;
}

std::vector<Vec3> PrbModel::joint_points(const Eigen::VectorXd& x) const {
  const std::vector<Frame> f = frames(x);
  std::vector<Vec3> pts;
  pts.reserve(4 * impl_->N);
  PrbLocal g;
  for (int j = 1; j <= impl_->N; ++j) {
    impl_->local(j, x.data() + kU * (j - 1), g);
    for (int q = 0; q < 3; ++q) pts.push_back(f[j - 1].transform(g.joint[q]));
    pts.push_back(f[j].p);
  }
  return pts;
}

Solution PrbModel::solve(LegacyWorkspace& workspace, const Solution* warm_start) const {
  const auto t0 = std::chrono::steady_clock::now();
  auto* ws = dynamic_cast<PrbWorkspace*>(&workspace);
  if (!ws) throw InputError("workspace", "", "not a workspace of the PRB model");
  const Impl& m = *impl_;

  Solution sol;
  sol.model = "prb";
  SolverSummary& sum = sol.summary;
  sum.linear_solver = "dense";
  sum.integrator = "none";
  Eigen::VectorXd full = Eigen::VectorXd::Zero(kU * m.N);
  PrbSystem system(m, *ws);
  sum.unknowns = system.size();

  if (m.J == 0) {
    sum.termination = TerminationType::Converged;
    sum.message = "no load: the robot is straight";
    sum.linear_solver = "none";
  } else {
    const bool warm = warm_start && warm_start->unknowns.size() == full.size() && warm_start->unknowns.allFinite();
    // Straight guess (all joint angles and twists zero); each bending plane is put where the
    // moment at the straight state points (y_phi along M*), see prb.hpp. With phi_ref = phi it
    // is the exact solution at load factor 0 (the start of load continuation).
    auto straight_guess = [&](Eigen::VectorXd& v) {
      v.setZero();
      system.evaluate(v.data());
      for (int j = 1; j <= m.J; ++j) {
        const Vec3 a = ws->frames[j - 1].R.transpose() * system.base_moment(j);
        const double scale = m.statics.length(j) / m.EI;
        v[kU * (j - 1) + 3] = scale * std::hypot(a.x(), a.y()) > 1e-14 ? std::atan2(-a.x(), a.y()) : 0.0;
      }
    };
    if (warm)
      full.head(kU * m.J) = warm_start->unknowns.head(kU * m.J);
    else
      straight_guess(full);
    for (int j = 1; j <= m.J; ++j) ws->phi_ref[j] = full[kU * (j - 1) + 3];
    Eigen::VectorXd x = full.head(kU * m.J);
    bvp::NewtonOptions opt = bvp::NewtonOptions::from(scene_.solver);
    opt.linear_solver = LinearSolverKind::Dense;
    // A Newton step changes the joint angles by at most about one radian in total: a longer
    // step from the straight guess can throw a strongly bent subsegment (n = 1) into the basin
    // where its bending plane is 90 deg off the moment, a local minimum of |F| (configurations
    // 14 and 15 of the case study at n = 1 end there with KINSOL's automatic bound).
    opt.max_newton_step = kMaxNewtonStep;
    const bvp::NewtonResult r = ws->newton.solve(system, x, opt);
    detail::copy_newton_result(r, sum);
    if (!r.converged() && scene_.solver.continuation) {
      straight_guess(full);
      for (int j = 1; j <= m.J; ++j) ws->phi_ref[j] = full[kU * (j - 1) + 3];
      x = full.head(kU * m.J);
      detail::continue_loads(ws->newton, system, x, opt, scene_.solver, sum);
    }
    full.head(kU * m.J) = x;
  }

  sol.disk_frames.resize(m.N + 1);
  m.compute_frames(full.data(), sol.disk_frames.data(), nullptr, nullptr);
  sol.tendon_displacements =
      tendon::chord_displacements(sol.disk_frames, m.statics.routing(), scene_.actuation.convention);
  sol.tensions = scene_.actuation.values;
  sol.unknowns = full;
  sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sol;
}

namespace detail {
std::unique_ptr<LegacyStaticModel> make_legacy_prb_model(const Scene& scene) { return std::make_unique<PrbModel>(scene); }
}  // namespace detail

}  // namespace tdcr
