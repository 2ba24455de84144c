#include "tdcr/models/ccsub.hpp"

#include <chrono>
#include <cmath>

#include "common/load_continuation.hpp"
#include "common/model_factories.hpp"
#include "common/newton_summary.hpp"
#include "common/subsegment_statics.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

namespace {

// Arc functions of the bending angle t, with series where the closed forms cancel:
// s1 = sin t / t, c2 = (1 - cos t) / t^2, g3 = (t - sin t) / t^3.
struct ArcCoefficients {
  double s1, c2, g3;
  explicit ArcCoefficients(double t2) {
    if (t2 < 1e-8) {
      s1 = 1.0 - t2 / 6.0 + t2 * t2 / 120.0;
      c2 = 0.5 - t2 / 24.0 + t2 * t2 / 720.0;
      g3 = 1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0;
    } else {
      const double t = std::sqrt(t2);
      const double s = std::sin(t), c = std::cos(t);
      s1 = s / t;
      c2 = (1.0 - c) / t2;
      g3 = (t - s) / (t2 * t);
    }
  }
};

}  // namespace

struct CcsubModel::Impl {
  detail::SubsegmentStatics statics;
  double EI = 0.0;
  double GJ = 0.0;
  int N = 0;  // subsegments
  int J = 0;  // loaded subsegments (unknowns 3J)

  explicit Impl(const Scene& scene) : statics(scene) {
    const BackboneStiffness k = scene.robot.backbone.effective_stiffness();
    EI = k.EI;
    GJ = k.GJ;
    N = statics.subsegments();
    J = statics.active_subsegments();
  }

  // Frames of all disks from the unknowns of subsegments 1..J (x has >= 3J values); subsegments
  // beyond J are straight. If centroids is not null, also the arc centroids (base frame).
  void compute_frames(const double* x, Frame* frames, Vec3* centroids) const {
    frames[0] = Frame{};
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
      const double bx = x[3 * (j - 1)], by = x[3 * (j - 1) + 1], eps = x[3 * (j - 1) + 2];
      const double t2 = bx * bx + by * by;
      const ArcCoefficients a(t2);
      // Arc end in the frame of disk j-1 (Eq. 5; the arc bends towards u x e_z = (u_y, -u_x)).
      const Vec3 p_loc(by * l * a.c2, -bx * l * a.c2, l * a.s1);
      // Rotation exp([u l]) R_z(eps) (Eq. 8 with the twist of Section 3.1).
      Mat3 Rb;
      const double c2 = a.c2;
      Rb << 1.0 - c2 * by * by, c2 * bx * by, a.s1 * by,
            c2 * bx * by, 1.0 - c2 * bx * bx, -a.s1 * bx,
            -a.s1 * by, a.s1 * bx, 1.0 - c2 * t2;
      const double ce = std::cos(eps), se = std::sin(eps);
      Mat3 Rl;
      Rl.col(0) = ce * Rb.col(0) + se * Rb.col(1);
      Rl.col(1) = -se * Rb.col(0) + ce * Rb.col(1);
      Rl.col(2) = Rb.col(2);
      f.R = prev.R * Rl;
      f.p = prev.p + prev.R * p_loc;
      if (centroids) {
        const Vec3 c_loc(by * l * a.g3, -bx * l * a.g3, l * a.c2);
        centroids[j] = prev.p + prev.R * c_loc;
      }
    }
  }
};

namespace {

class CcsubWorkspace final : public LegacyWorkspace {
 public:
  bvp::NewtonSolver newton;
  std::vector<Frame> frames;
  std::vector<Vec3> centroids, F, M;
};

// The 3J residuals of Eq. 43 with the recursive balance Eq. 44-47 (see ccsub.hpp). Its
// parameter is the load factor (continuation): the balance is linear in the loads, so scaling
// every load by lambda scales the moments M_j by lambda.
class CcsubSystem final : public bvp::ParameterizedSystem {
 public:
  CcsubSystem(const CcsubModel::Impl& m, CcsubWorkspace& ws) : m_(m), ws_(ws) {
    ws_.frames.resize(m.N + 1);
    ws_.centroids.assign(m.N + 1, Vec3::Zero());
    ws_.F.assign(m.N + 1, Vec3::Zero());
    ws_.M.assign(m.N + 1, Vec3::Zero());
  }
  int size() const override { return 3 * m_.J; }
  void set_parameter(double lambda) override { load_ = lambda; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    const bool bb = m_.statics.has_backbone_weight();
    Frame* fr = ws_.frames.data();
    m_.compute_frames(x.data(), fr, bb ? ws_.centroids.data() : nullptr);
    m_.statics.distal_wrenches(fr, ws_.centroids.data(), ws_.F.data(), ws_.M.data());
    const double gj_ei = m_.GJ / m_.EI;
    for (int j = 1; j <= m_.J; ++j) {
      const Frame& a = fr[j - 1];
      // Moment about O_{j-1} of everything distal of disk j-1 (Eq. 45, 47).
      Vec3 Mb = ws_.M[j] + (fr[j].p - a.p).cross(ws_.F[j]);
      if (bb) Mb += (ws_.centroids[j] - a.p).cross(m_.statics.backbone_weight(j));
      const Vec3 m_loc = load_ * (a.R.transpose() * Mb);
      const Vec3 z_loc = a.R.transpose() * fr[j].R.col(2);
      const double s = m_.statics.length(j) / m_.EI;
      const int i = 3 * (j - 1);
      // Eq. 43 scaled by l/EI: l u + (GJ/EI) eps z_j - (l/EI) M_j = 0, frame of disk j-1.
      f[i] = x[i] + gj_ei * x[i + 2] * z_loc.x() - s * m_loc.x();
      f[i + 1] = x[i + 1] + gj_ei * x[i + 2] * z_loc.y() - s * m_loc.y();
      f[i + 2] = gj_ei * x[i + 2] * z_loc.z() - s * m_loc.z();
    }
    return f.allFinite();
  }

 private:
  const CcsubModel::Impl& m_;
  CcsubWorkspace& ws_;
  double load_ = 1.0;
};

}  // namespace

CcsubModel::CcsubModel(const Scene& scene) : scene_(scene) {
  scene_.validate();
  if (scene_.actuation.kind != Actuation::Kind::Tensions)
    throw InputError("actuation.kind", "displacements", "the CCsub model is driven by tendon tensions");
  impl_ = std::make_unique<Impl>(scene_);
}

CcsubModel::~CcsubModel() = default;

std::unique_ptr<LegacyWorkspace> CcsubModel::make_workspace() const { return std::make_unique<CcsubWorkspace>(); }

std::vector<Frame> CcsubModel::frames(const Eigen::VectorXd& x) const {
  if (x.size() != 3 * impl_->N)
    throw InputError("unknowns", std::to_string(x.size()), "expected 3 unknowns per subsegment");
  std::vector<Frame> f(impl_->N + 1);
  impl_->compute_frames(x.data(), f.data(), nullptr);
  return f;
}

Solution CcsubModel::solve(LegacyWorkspace& workspace, const Solution* warm_start) const {
  const auto t0 = std::chrono::steady_clock::now();
  auto* ws = dynamic_cast<CcsubWorkspace*>(&workspace);
  if (!ws) throw InputError("workspace", "", "not a workspace of the CCsub model");
  const Impl& m = *impl_;

  Solution sol;
  sol.model = "ccsub";
  SolverSummary& sum = sol.summary;
  sum.linear_solver = "dense";
  sum.integrator = "none";
  Eigen::VectorXd full = Eigen::VectorXd::Zero(3 * m.N);
  if (warm_start && warm_start->unknowns.size() == full.size() && warm_start->unknowns.allFinite())
    full.head(3 * m.J) = warm_start->unknowns.head(3 * m.J);

  CcsubSystem system(m, *ws);
  sum.unknowns = system.size();
  if (m.J == 0) {
    sum.termination = TerminationType::Converged;
    sum.message = "no load: the robot is straight";
    sum.linear_solver = "none";
  } else {
    Eigen::VectorXd x = full.head(3 * m.J);
    bvp::NewtonOptions opt = bvp::NewtonOptions::from(scene_.solver);
    opt.linear_solver = LinearSolverKind::Dense;
    const bvp::NewtonResult r = ws->newton.solve(system, x, opt);
    detail::copy_newton_result(r, sum);
    if (!r.converged() && scene_.solver.continuation) {
      x.setZero();  // the straight robot, exact at load factor 0
      detail::continue_loads(ws->newton, system, x, opt, scene_.solver, sum);
    }
    full.head(3 * m.J) = x;
  }

  sol.disk_frames.resize(m.N + 1);
  m.compute_frames(full.data(), sol.disk_frames.data(), nullptr);
  sol.tendon_displacements =
      tendon::chord_displacements(sol.disk_frames, m.statics.routing(), scene_.actuation.convention);
  sol.tensions = scene_.actuation.values;
  sol.unknowns = full;
  sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sol;
}

namespace detail {
std::unique_ptr<LegacyStaticModel> make_legacy_ccsub_model(const Scene& scene) { return std::make_unique<CcsubModel>(scene); }
}  // namespace detail

}  // namespace tdcr
