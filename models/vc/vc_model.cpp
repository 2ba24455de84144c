// The VC model: Cosserat rod with fully constrained tendons, single shooting (see vc.hpp).
#include "tdcr/models/vc.hpp"

#include <algorithm>
#include <limits>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include "common/load_continuation.hpp"
#include "common/model_factories.hpp"
#include "common/newton_summary.hpp"
#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/integrator.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/bvp/residual_system.hpp"
#include "tdcr/bvp/shooting.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/cosserat_rod.hpp"

namespace tdcr {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

/// Bound on the scaled Newton step (KINSOL mxnewtstep), see solve().
constexpr double kMaxNewtonStep = 1.0;

namespace {

/// A tensioned tendon as the right-hand side sees it (body-frame offset, its hat, tension).
struct TendonTerm {
  Vec3 r = Vec3::Zero();
  Mat3 rx = Mat3::Zero();
  double T = 0.0;
};

/// A tendon whose length is integrated (every tendon through the segment, tensioned or not).
struct LengthTerm {
  Vec3 r = Vec3::Zero();
  int index = 0;
};

/// Loads of one segment at the current load factor.
struct SegmentLoads {
  std::vector<TendonTerm> tendons;      ///< T > 0, running through the segment.
  std::vector<TendonTerm> terminating;  ///< T > 0, ending at the segment's end.
  std::vector<LengthTerm> lengths;      ///< Every tendon running through the segment.
};

/// Everything the scene applies, at load factor lambda (continuation scales it).
struct LoadCase {
  std::vector<SegmentLoads> segments;
  std::vector<Vec3> disk_weight;  ///< m_d g per disk (index 0 = base disk, unused).
  Vec3 weight = Vec3::Zero();     ///< rho A g (N/m, base frame).
  Vec3 tip_force = Vec3::Zero();
  Vec3 tip_moment = Vec3::Zero();
};

}  // namespace

struct VcModel::Impl {
  TendonRouting routing;
  cosserat::Section section;
  Vec3 kse = Vec3::Zero();  // GA, GA, EA
  Vec3 kbt = Vec3::Zero();  // EI, EI, GJ
  bool shear = true;
  bool backbone_weight = false;
  bool disk_weight = false;
  bool tip_wrench = false;
  bool kink_forces = true;
  bool lengths_in_shots = false;  // CVODE: integrate tendon lengths in every shot
  int tendon_count = 0;
  double length = 0.0;
  double force_scale = 1.0;
  double moment_scale = 1.0;
  LoadCase full;  // the scene's loads at lambda = 1
  std::vector<double> tensions;
  Vec3 weight_total = Vec3::Zero();
  Vec3 weight_moment = Vec3::Zero();  // sum over weights of p x W for the straight robot
  double tension_parameter = 0.0;     // L^2 (|W| + |F_tip|) / EI, see vc.hpp
  bool multiple_shooting = false;     // formulation chosen once in the constructor
  std::vector<int> interval_segment;  // segment of disk interval k (disk k to disk k+1)
};

namespace {

/// The rod ODE of one segment (18 states, plus one length per tendon if requested).
class RodOde final : public bvp::OdeSystem {
 public:
  using Fn = void (*)(const RodOde&, const double*, double*);

  RodOde(const VcModel::Impl& model, bool lengths) : model_(model), lengths_(lengths) {
    if (model.shear)
      fn_ = model.backbone_weight ? &rhs_impl<true, true> : &rhs_impl<true, false>;
    else
      fn_ = model.backbone_weight ? &rhs_impl<false, true> : &rhs_impl<false, false>;
  }
  int dimension() const override { return cosserat::kStateSize + (lengths_ ? model_.tendon_count : 0); }
  void rhs(double, const double* y, double* dyds) const override { fn_(*this, y, dyds); }
  void set(const SegmentLoads* seg, const Vec3* weight) {
    seg_ = seg;
    weight_ = weight;
  }

 private:
  template <bool Shear, bool Gravity>
  static void rhs_impl(const RodOde& o, const double* y, double* dyds) {
    const VcModel::Impl& M = o.model_;
    const Eigen::Map<const Mat3> R = cosserat::rotation(y);
    const Vec3 n = cosserat::force(y);
    const Vec3 m = cosserat::moment(y);
    const Vec3 nb = R.transpose() * n;
    const Vec3 mb = R.transpose() * m;
    const Vec3 u = M.section.inv_kbt.cwiseProduct(mb);
    Vec3 v = Vec3::UnitZ();
    if constexpr (Shear) v += M.section.inv_kse.cwiseProduct(nb);
    const Vec3 dp = R * v;
    cosserat::position(dyds) = dp;
    cosserat::rotation(dyds) = R * lie::hat(u);

    const std::vector<TendonTerm>& tendons = o.seg_->tendons;
    if (tendons.empty()) {
      // Free rod: no tendon load, no linear solve.
      if constexpr (Gravity)
        cosserat::force(dyds) = -*o.weight_;
      else
        cosserat::force(dyds).setZero();
      cosserat::moment(dyds) = -dp.cross(n);
    } else {
      Mat3 sumA = Mat3::Zero();    // sum A_k
      Mat3 sumAr = Mat3::Zero();   // sum A_k [r_k]x
      Mat3 sumrAr = Mat3::Zero();  // sum [r_k]x A_k [r_k]x
      Vec3 suma = Vec3::Zero();    // sum a_k
      Vec3 sumra = Vec3::Zero();   // sum r_k x a_k
      for (const TendonTerm& t : tendons) {
        const Vec3 q = v + u.cross(t.r);
        const double inv_q = 1.0 / q.norm();
        const Vec3 tk = q * inv_q;
        const double c = t.T * inv_q;
        const Mat3 A = c * (Mat3::Identity() - tk * tk.transpose());
        const Vec3 a = c * u.cross(q);
        const Mat3 Ar = A * t.rx;
        if constexpr (Shear) sumA += A;
        sumAr += Ar;
        sumrAr.noalias() += t.rx * Ar;
        suma += a;
        sumra += t.r.cross(a);
      }
      Vec3 fe_b = Vec3::Zero();
      if constexpr (Gravity) fe_b = R.transpose() * *o.weight_;
      const Vec3 b_m = -u.cross(mb) - v.cross(nb) - sumra;
      if constexpr (Shear) {
        Mat6 K;
        K.topLeftCorner<3, 3>() = sumA;
        K.topLeftCorner<3, 3>().diagonal() += M.kse;
        K.topRightCorner<3, 3>() = -sumAr;
        K.bottomLeftCorner<3, 3>() = -sumAr.transpose();  // = sum [r]x A (A symmetric)
        K.bottomRightCorner<3, 3>() = -sumrAr;
        K.bottomRightCorner<3, 3>().diagonal() += M.kbt;
        Vec6 b;
        b.head<3>() = -u.cross(nb) - suma - fe_b;
        b.tail<3>() = b_m;
        const Vec6 x = K.llt().solve(b);
        const Vec3 vs = x.head<3>();
        const Vec3 us = x.tail<3>();
        cosserat::force(dyds) = R * (M.kse.cwiseProduct(vs) + u.cross(nb));
        cosserat::moment(dyds) = R * (M.kbt.cwiseProduct(us) + u.cross(mb));
      } else {
        Mat3 K = -sumrAr;
        K.diagonal() += M.kbt;
        const Vec3 us = K.llt().solve(b_m);
        // Body-frame tendon force sum a_k + A_k (u_s x r_k) = sum a_k - (sum A_k [r_k]x) u_s.
        const Vec3 fb = suma - sumAr * us;
        Vec3 dn = -(R * fb);
        if constexpr (Gravity) dn -= *o.weight_;
        cosserat::force(dyds) = dn;
        cosserat::moment(dyds) = R * (M.kbt.cwiseProduct(us) + u.cross(mb));
      }
    }
    if (o.lengths_) {
      double* dl = dyds + cosserat::kStateSize;
      for (int k = 0; k < M.tendon_count; ++k) dl[k] = 0.0;
      for (const LengthTerm& t : o.seg_->lengths) dl[t.index] = (v + u.cross(t.r)).norm();
    }
  }

  const VcModel::Impl& model_;
  bool lengths_;
  Fn fn_ = nullptr;
  const SegmentLoads* seg_ = nullptr;
  const Vec3* weight_ = nullptr;
};

/// What the final pass records.
struct Record {
  std::vector<Frame>* frames = nullptr;
  std::vector<BackboneSample>* samples = nullptr;
  std::vector<double>* segment_end_lengths = nullptr;  // [segment * K + k]
};

}  // namespace

struct VcWorkspace::Impl {
  std::unique_ptr<bvp::Integrator> shot_integrator;
  std::unique_ptr<bvp::Integrator> final_integrator;  // may alias shot_integrator (CVODE)
  bvp::NewtonSolver newton;
  std::unique_ptr<RodOde> shot_rod;
  std::unique_ptr<RodOde> final_rod;
  LoadCase loads;
  Eigen::VectorXd y;
  Eigen::VectorXd x;
  double lambda = -1.0;
  // The model this workspace was prepared for (its ODEs and loads refer to it).
  std::shared_ptr<const VcModel::Impl> owner;
  // Multiple shooting (built on first use).
  std::vector<std::unique_ptr<bvp::OdeSystem>> ms_rods;  // one RodOde per segment
  std::unique_ptr<bvp::ShootingProblem> ms_problem;
  std::unique_ptr<bvp::ShootingSystem> ms_shooting;
  std::unique_ptr<bvp::ParameterizedSystem> ms_system;
};

VcWorkspace::~VcWorkspace() = default;

long VcWorkspace::rhs_evaluations() const {
  if (!impl || !impl->shot_integrator) return 0;
  long n = impl->shot_integrator->rhs_evaluations();
  if (impl->final_integrator.get() != nullptr) n += impl->final_integrator->rhs_evaluations();
  return n;
}

namespace {

/// The scaled loads at factor lambda, written into `out` (allocation-free once sized).
void scale_loads(const LoadCase& full, double lambda, LoadCase& out) {
  out.segments.resize(full.segments.size());
  for (std::size_t i = 0; i < full.segments.size(); ++i) {
    out.segments[i] = full.segments[i];
    for (TendonTerm& t : out.segments[i].tendons) t.T *= lambda;
    for (TendonTerm& t : out.segments[i].terminating) t.T *= lambda;
  }
  out.disk_weight = full.disk_weight;
  for (Vec3& w : out.disk_weight) w *= lambda;
  out.weight = lambda * full.weight;
  out.tip_force = lambda * full.tip_force;
  out.tip_moment = lambda * full.tip_moment;
}

/// Point loads at disk j (the end of an interval of segment i), applied to the rod state y
/// (18 values, first): tendon terminations (Eq. 40-41), the disk's weight and the kink forces of
/// passing tendons. False if the kink fixed-point iteration did not settle.
bool disk_point_loads(const VcModel::Impl& M, const LoadCase& L, int i, int j, double* y) {
  const TendonRouting& rt = M.routing;
  const int nseg = static_cast<int>(L.segments.size());
  const SegmentLoads& seg = L.segments[i];
  const int last = rt.segment_end_disk[i];
  const bool terminates = j == last && !seg.terminating.empty();
  const bool weighted = M.disk_weight && L.disk_weight[j].squaredNorm() > 0.0;
  if (terminates || weighted) {
    // Point loads at disk j, with u, v just proximal of it.
    const Mat3 R = cosserat::rotation(static_cast<const double*>(y));
    const Vec3 u = M.section.curvature(R, cosserat::moment(y));
    const Vec3 v = M.section.strain(R, cosserat::force(y));
    if (terminates) {
      // Eq. 40-41: tendon termination forces F_k = -T_k R t_k at p + R r_k.
      Vec3 dn = Vec3::Zero(), dm = Vec3::Zero();
      for (const TendonTerm& t : seg.terminating) {
        const Vec3 q = v + u.cross(t.r);
        const Vec3 F = -(t.T / q.norm()) * (R * q);
        dn += F;
        dm += (R * t.r).cross(F);
      }
      cosserat::force(y) -= dn;
      cosserat::moment(y) -= dm;
    }
    if (weighted) cosserat::force(y) -= L.disk_weight[j];
    // Kinks: the point loads make u, v jump, so every tensioned tendon continuing past disk j
    // changes direction there and pulls on the backbone with T_k R (t_k+ - t_k-) at
    // p + R r_k. t_k+ depends on the wrench after the kink: fixed-point iteration (its
    // contraction factor is about T r^2 / EI, small for any sane tension).
    const std::vector<TendonTerm>* cont = nullptr;
    if (j < last)
      cont = &seg.tendons;
    else if (i + 1 < nseg)
      cont = &L.segments[i + 1].tendons;
    if (M.kink_forces && cont && !cont->empty()) {
      const Vec3 n_base = cosserat::force(y), m_base = cosserat::moment(y);
      Vec3 np = n_base, mp = m_base;
      bool settled = false;
      for (int it = 0; it < 100 && !settled; ++it) {
        const Vec3 up = M.section.curvature(R, mp);
        const Vec3 vp = M.section.strain(R, np);
        Vec3 dn = Vec3::Zero(), dm = Vec3::Zero();
        for (const TendonTerm& t : *cont) {
          const Vec3 qm = v + u.cross(t.r);
          const Vec3 qp = vp + up.cross(t.r);
          const Vec3 K = t.T * (R * (qp / qp.norm() - qm / qm.norm()));
          dn += K;
          dm += (R * t.r).cross(K);
        }
        const Vec3 n_new = n_base - dn, m_new = m_base - dm;
        settled = (n_new - np).norm() <= 1e-15 * M.force_scale && (m_new - mp).norm() <= 1e-15 * M.moment_scale;
        np = n_new;
        mp = m_new;
      }
      if (!settled) return false;
      cosserat::force(y) = np;
      cosserat::moment(y) = mp;
    }
  }
  return true;
}

/// One shot from the base. `y` has room for the rod's dimension. Returns false if integration
/// failed; otherwise `res` = (n(L+) - F_tip, m(L+) - M_tip).
bool shoot_impl(const VcModel::Impl& M, const LoadCase& L, bvp::Integrator& integ, RodOde& rod, double* y,
                const Vec6& x, Vec6& res, const Record* rec) {
  const int dim = rod.dimension();
  for (int i = 0; i < dim; ++i) y[i] = 0.0;
  cosserat::rotation(y) = Mat3::Identity();
  cosserat::force(y) = x.head<3>();
  cosserat::moment(y) = x.tail<3>();
  const TendonRouting& rt = M.routing;
  if (rec) {
    rec->frames->push_back(Frame{});
    rec->samples->push_back(BackboneSample{0.0, Frame{}, x.head<3>(), x.tail<3>()});
  }
  const int nseg = static_cast<int>(L.segments.size());
  for (int i = 0; i < nseg; ++i) {
    const SegmentLoads& seg = L.segments[i];
    rod.set(&seg, &L.weight);
    const int last = rt.segment_end_disk[i];
    const int first = i == 0 ? 1 : rt.segment_end_disk[i - 1] + 1;
    for (int j = first; j <= last; ++j) {
      if (!integ.integrate(rod, rt.disk_s[j - 1], rt.disk_s[j], y)) return false;
      if (!disk_point_loads(M, L, i, j, y)) return false;
      if (rec) {
        const Frame f = cosserat::frame_of(y);
        rec->frames->push_back(f);
        rec->samples->push_back(
            BackboneSample{rt.disk_s[j], f, Vec3(cosserat::force(y)), Vec3(cosserat::moment(y))});
      }
    }
    if (rec && rec->segment_end_lengths && dim > cosserat::kStateSize)
      for (int k = 0; k < M.tendon_count; ++k)
        (*rec->segment_end_lengths)[i * M.tendon_count + k] = y[cosserat::kStateSize + k];
  }
  res.head<3>() = cosserat::force(y);
  res.tail<3>() = cosserat::moment(y);
  if (M.tip_wrench) {
    res.head<3>() -= L.tip_force;
    res.tail<3>() -= L.tip_moment;
  }
  return res.allFinite();
}

void set_lambda(const VcModel::Impl& M, VcWorkspace::Impl& W, double lambda);

/// The shooting problem as KINSOL sees it; its parameter is the load factor (continuation).
class ShootingSystem final : public bvp::ParameterizedSystem {
 public:
  ShootingSystem(const VcModel::Impl& M, VcWorkspace::Impl& W) : M_(M), W_(W) {}
  int size() const override { return 6; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    const Vec6 xx = x;
    Vec6 r;
    if (!shoot_impl(M_, W_.loads, *W_.shot_integrator, *W_.shot_rod, W_.y.data(), xx, r, nullptr)) return false;
    f = r;
    return true;
  }
  // Forward-difference Jacobian by the solver (6 extra shots), with increments
  // sqrt(max(eps, relative_noise)): sqrt(eps) for RK4, sqrt(rtol) for CVODE.
  double relative_noise() const override { return W_.shot_integrator->relative_noise(); }
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override {
    s.head<3>().setConstant(1.0 / M_.force_scale);
    s.tail<3>().setConstant(1.0 / M_.moment_scale);
  }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { residual_scale(s); }
  void set_parameter(double lambda) override { set_lambda(M_, W_, lambda); }

 private:
  const VcModel::Impl& M_;
  VcWorkspace::Impl& W_;
};

void prepare_workspace(const std::shared_ptr<const VcModel::Impl>& model, const SolverOptions& opt,
                       VcWorkspace::Impl& W) {
  if (W.owner != model) {
    // A workspace used by another model: its loads, ODEs and integrators describe that model.
    // Keep only the Newton workspace (KINSOL memory is rebuilt by size anyway).
    W.ms_system.reset();
    W.ms_shooting.reset();
    W.ms_problem.reset();
    W.ms_rods.clear();
    W.shot_rod.reset();
    W.final_rod.reset();
    W.shot_integrator.reset();
    W.final_integrator.reset();
    W.lambda = -1.0;
    W.owner = model;
  }
  const VcModel::Impl& M = *model;
  if (W.shot_integrator) return;
  W.shot_integrator = bvp::make_integrator(opt);
  W.shot_rod = std::make_unique<RodOde>(M, M.lengths_in_shots);
  W.final_rod = std::make_unique<RodOde>(M, true);
  if (!M.lengths_in_shots) W.final_integrator = bvp::make_integrator(opt);
  W.y = Eigen::VectorXd::Zero(cosserat::kStateSize + M.tendon_count);
  W.x = Eigen::VectorXd::Zero(6);
}

void set_lambda(const VcModel::Impl& M, VcWorkspace::Impl& W, double lambda) {
  if (W.lambda == lambda) return;
  scale_loads(M.full, lambda, W.loads);
  W.lambda = lambda;
}


/// Multiple shooting: one interval per disk interval, unknowns = the 18 rod states (p, R, n, m)
/// at every interval start (just distal of the disk's point loads). Junction at disk i:
/// y_i^+ - J_i(y_{i-1}^-), J_i = the point loads of disk i; boundary: p(0) = 0, R(0) = I and
/// the tip wrench after the tip disk's point loads.
class MsProblem final : public bvp::ShootingProblem {
 public:
  MsProblem(const VcModel::Impl& M, VcWorkspace::Impl& W) : M_(M), W_(W) {}
  int state_dimension() const override { return cosserat::kStateSize; }
  int intervals() const override { return static_cast<int>(M_.interval_segment.size()); }
  double node(int k) const override { return M_.routing.disk_s[k]; }
  const bvp::OdeSystem& ode(int k) const override { return *W_.ms_rods[M_.interval_segment[k]]; }
  void boundary(const bvp::ShootingNodes& nodes, double* r) const override {
    const double* y0 = nodes.start(0);
    for (int i = 0; i < 3; ++i) r[i] = y0[i];
    Eigen::Map<Mat3>(r + 3) = cosserat::rotation(y0) - Mat3::Identity();
    const int N = intervals();
    std::copy(nodes.end(N - 1), nodes.end(N - 1) + cosserat::kStateSize, buf_);
    if (!disk_point_loads(M_, W_.loads, M_.interval_segment[N - 1], N, buf_)) {
      for (int i = 12; i < 18; ++i) r[i] = std::numeric_limits<double>::quiet_NaN();
      return;
    }
    Eigen::Map<Vec3>(r + 12) = cosserat::force(static_cast<const double*>(buf_)) - W_.loads.tip_force;
    Eigen::Map<Vec3>(r + 15) = cosserat::moment(static_cast<const double*>(buf_)) - W_.loads.tip_moment;
  }
  void junction(int i, const bvp::ShootingNodes& nodes, double* r) const override {
    std::copy(nodes.end(i - 1), nodes.end(i - 1) + cosserat::kStateSize, buf_);
    const bool ok = disk_point_loads(M_, W_.loads, M_.interval_segment[i - 1], i, buf_);
    const double* yi = nodes.start(i);
    for (int k = 0; k < cosserat::kStateSize; ++k)
      r[k] = ok ? yi[k] - buf_[k] : std::numeric_limits<double>::quiet_NaN();
  }
  void state_scale(double* s) const override {
    for (int k = 0; k < 3; ++k) s[k] = 1.0 / M_.length;
    for (int k = 3; k < 12; ++k) s[k] = 1.0;
    for (int k = 12; k < 15; ++k) s[k] = 1.0 / M_.force_scale;
    for (int k = 15; k < 18; ++k) s[k] = 1.0 / M_.moment_scale;
  }

 private:
  const VcModel::Impl& M_;
  VcWorkspace::Impl& W_;
  mutable double buf_[cosserat::kStateSize] = {};
};

/// The multiple-shooting system with the load factor as its parameter (continuation).
class MsSystem final : public bvp::ParameterizedSystem {
 public:
  MsSystem(const VcModel::Impl& M, VcWorkspace::Impl& W, bvp::ShootingSystem& sys) : M_(M), W_(W), sys_(sys) {}
  int size() const override { return sys_.size(); }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    return sys_.residual(x, f) && f.allFinite();
  }
  const bvp::SparsityPattern* sparsity() const override { return sys_.sparsity(); }
  bool has_jacobian() const override { return true; }
  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& f,
                       double* values) override {
    return sys_.sparse_jacobian(x, f, values);
  }
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override { sys_.residual_scale(s); }
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override { sys_.unknown_scale(s); }
  double relative_noise() const override { return sys_.relative_noise(); }
  void set_parameter(double lambda) override { set_lambda(M_, W_, lambda); }

 private:
  const VcModel::Impl& M_;
  VcWorkspace::Impl& W_;
  bvp::ShootingSystem& sys_;
};

void prepare_multiple_shooting(const VcModel::Impl& M, VcWorkspace::Impl& W) {
  if (W.ms_system) return;
  for (std::size_t i = 0; i < M.full.segments.size(); ++i) {
    auto rod = std::make_unique<RodOde>(M, false);
    rod->set(&W.loads.segments[i], &W.loads.weight);
    W.ms_rods.push_back(std::move(rod));
  }
  W.ms_problem = std::make_unique<MsProblem>(M, W);
  W.ms_shooting = std::make_unique<bvp::ShootingSystem>(*W.ms_problem, *W.shot_integrator);
  W.ms_system = std::make_unique<MsSystem>(M, W, *W.ms_shooting);
}

/// Node states of the straight robot under the loads at factor `lambda` (the straight-robot
/// statics of every cut: the multiple-shooting analogue of VcInitialGuess::Equilibrium).
void straight_node_states(const VcModel::Impl& M, double lambda, Eigen::VectorXd& x) {
  const int N = static_cast<int>(M.interval_segment.size());
  const TendonRouting& rt = M.routing;
  const double L = M.length;
  for (int k = 0; k < N; ++k) {
    double* y = x.data() + static_cast<long>(k) * cosserat::kStateSize;
    const double s = rt.disk_s[k];
    Vec3 n = M.full.tip_force + (L - s) * M.full.weight;
    Vec3 m = M.full.tip_moment + ((L - s) * Vec3::UnitZ()).cross(M.full.tip_force) +
             (0.5 * (L - s) * (L - s) * Vec3::UnitZ()).cross(M.full.weight);
    for (int j = k + 1; j < rt.disk_count(); ++j) {
      n += M.full.disk_weight[j];
      m += ((rt.disk_s[j] - s) * Vec3::UnitZ()).cross(M.full.disk_weight[j]);
    }
    for (const RoutedTendon& t : rt.tendons)
      if (t.end_disk > k) {
        const double T = M.tensions[t.index];
        n -= T * Vec3::UnitZ();
        m += T * Vec3::UnitZ().cross(t.r);
      }
    cosserat::position(y) = s * Vec3::UnitZ();
    cosserat::rotation(y) = Mat3::Identity();
    cosserat::force(y) = lambda * n;
    cosserat::moment(y) = lambda * m;
  }
}

}  // namespace

VcModel::VcModel(const Scene& scene, VcOptions options) : scene_(scene), options_(options) {
  scene_.validate();
  if (scene_.actuation.kind != Actuation::Kind::Tensions)
    throw InputError("actuation.kind", "displacements", "the VC model is driven by tensions");
  auto impl = std::make_shared<Impl>();
  Impl& M = *impl;
  const Robot& robot = scene_.robot;
  const SceneEffects e = scene_.active_effects();
  M.routing = TendonRouting::from(robot);
  M.section = cosserat::Section::from(scene_);
  const BackboneStiffness k = robot.backbone.effective_stiffness();
  M.kse = Vec3(k.GA, k.GA, k.EA);
  M.kbt = Vec3(k.EI, k.EI, k.GJ);
  M.shear = e.shear_extension;
  M.backbone_weight = e.backbone_weight;
  M.disk_weight = e.disk_weight;
  M.tip_wrench = e.tip_wrench;
  M.kink_forces = options_.kink_forces;
  M.lengths_in_shots = scene_.solver.integrator == IntegratorKind::Cvode;
  M.tendon_count = static_cast<int>(M.routing.tendons.size());
  M.length = robot.total_length();
  M.tensions = scene_.actuation.values;

  const int nseg = static_cast<int>(robot.segments.size());
  M.full.segments.resize(nseg);
  double sum_T = 0.0, r_max = 0.0;
  for (const RoutedTendon& t : M.routing.tendons) {
    const double T = M.tensions[t.index];
    TendonTerm term{t.r, lie::hat(t.r), T};
    for (int i = 0; i <= t.segment; ++i) {
      M.full.segments[i].lengths.push_back(LengthTerm{t.r, t.index});
      if (T > 0.0) M.full.segments[i].tendons.push_back(term);
    }
    if (T > 0.0) {
      M.full.segments[t.segment].terminating.push_back(term);
      sum_T += T;
      r_max = std::max(r_max, t.r.norm());
    }
  }
  M.full.disk_weight.assign(M.routing.disk_count(), Vec3::Zero());
  if (e.disk_weight)
    for (int j = 1; j < M.routing.disk_count(); ++j) {
      M.full.disk_weight[j] = robot.segments[M.routing.disk_segment[j]].disk_mass * scene_.loads.gravity;
      M.weight_total += M.full.disk_weight[j];
      M.weight_moment += (M.routing.disk_s[j] * Vec3::UnitZ()).cross(M.full.disk_weight[j]);
    }
  if (e.backbone_weight) {
    M.full.weight = M.section.weight;
    M.weight_total += M.length * M.section.weight;
    M.weight_moment += (0.5 * M.length * M.length * Vec3::UnitZ()).cross(M.section.weight);
  }
  if (e.tip_wrench) {
    M.full.tip_force = scene_.loads.tip_force;
    M.full.tip_moment = scene_.loads.tip_moment;
  }
  const double ext = M.full.tip_force.norm() + M.weight_total.norm();
  M.force_scale = sum_T + ext + 1e-3;
  M.moment_scale = sum_T * r_max + ext * M.length + M.full.tip_moment.norm() + 1e-3 * M.length;
  M.interval_segment.assign(M.routing.disk_segment.begin() + 1, M.routing.disk_segment.end());
  M.tension_parameter = M.length * M.length * ext / k.EI;
  switch (options_.formulation) {
    case VcFormulation::SingleShooting: M.multiple_shooting = false; break;
    case VcFormulation::MultipleShooting: M.multiple_shooting = true; break;
    case VcFormulation::Automatic:
      M.multiple_shooting = M.tension_parameter > options_.multiple_shooting_threshold;
      break;
  }
  impl_ = std::move(impl);
}

VcModel::~VcModel() = default;

std::unique_ptr<LegacyWorkspace> VcModel::make_workspace() const {
  auto ws = std::make_unique<VcWorkspace>();
  ws->impl = std::make_unique<VcWorkspace::Impl>();
  return ws;
}

Vec6 VcModel::initial_guess(VcInitialGuess guess) const {
  Vec6 x = Vec6::Zero();
  if (guess == VcInitialGuess::Zero) return x;
  const Impl& M = *impl_;
  double sum_T = 0.0;
  Vec3 tm = Vec3::Zero();
  for (const RoutedTendon& t : M.routing.tendons) {
    const double T = M.tensions[t.index];
    sum_T += T;
    tm += T * Vec3::UnitZ().cross(t.r);
  }
  x.head<3>() = M.full.tip_force + M.weight_total - sum_T * Vec3::UnitZ();
  x.tail<3>() = M.full.tip_moment + (M.length * Vec3::UnitZ()).cross(M.full.tip_force) + M.weight_moment + tm;
  return x;
}

Vec6 VcModel::residual_scale() const {
  Vec6 s;
  s.head<3>().setConstant(1.0 / impl_->force_scale);
  s.tail<3>().setConstant(1.0 / impl_->moment_scale);
  return s;
}

double VcModel::tension_parameter() const { return impl_->tension_parameter; }
bool VcModel::uses_multiple_shooting() const { return impl_->multiple_shooting; }

bool VcModel::shoot(VcWorkspace& ws, const Vec6& x, Vec6& residual) const {
  if (!ws.impl) ws.impl = std::make_unique<VcWorkspace::Impl>();
  prepare_workspace(impl_, scene_.solver, *ws.impl);
  set_lambda(*impl_, *ws.impl, 1.0);
  VcWorkspace::Impl& W = *ws.impl;
  return shoot_impl(*impl_, W.loads, *W.shot_integrator, *W.shot_rod, W.y.data(), x, residual, nullptr);
}

bool VcModel::warm_reaction(const Solution& previous, Vec6& x) const {
  const Impl& M = *impl_;
  const int nd = M.routing.disk_count();
  if (static_cast<int>(previous.disk_frames.size()) != nd || static_cast<int>(previous.backbone.size()) != nd)
    return false;
  // Tendon directions at the base from the previous strains (R(0) = I).
  const Vec3 u0 = M.section.curvature(Mat3::Identity(), previous.backbone[0].m);
  const Vec3 v0 = M.section.strain(Mat3::Identity(), previous.backbone[0].n);
  Vec3 n = M.full.tip_force, m = M.full.tip_moment + previous.disk_frames.back().p.cross(M.full.tip_force);
  for (const RoutedTendon& t : M.routing.tendons) {
    const double T = M.tensions[t.index];
    if (T <= 0.0) continue;
    const Vec3 pull = T * (v0 + u0.cross(t.r)).normalized();  // the tendon's pull on the robot at the base
    n -= pull;
    m -= t.r.cross(pull);
  }
  if (M.disk_weight)
    for (int j = 1; j < nd; ++j) {
      n += M.full.disk_weight[j];
      m += previous.disk_frames[j].p.cross(M.full.disk_weight[j]);
    }
  if (M.backbone_weight) {
    // Integral of p over the backbone: trapezoid between disks with the end correction
    // h^2/12 (p'(a) - p'(b)), p' ~ R e_z (fourth order, Euler-Maclaurin).
    Vec3 integral = Vec3::Zero();
    for (int j = 1; j < nd; ++j) {
      const Frame& a = previous.disk_frames[j - 1];
      const Frame& b = previous.disk_frames[j];
      const double h = M.routing.disk_s[j] - M.routing.disk_s[j - 1];
      integral += 0.5 * h * (a.p + b.p) + (h * h / 12.0) * (a.R.col(2) - b.R.col(2));
    }
    n += M.length * M.full.weight;
    m += integral.cross(M.full.weight);
  }
  x.head<3>() = n;
  x.tail<3>() = m;
  return x.allFinite();
}

Solution VcModel::solve(LegacyWorkspace& workspace, const Solution* warm_start) const {
  const auto t0 = std::chrono::steady_clock::now();
  auto* ws = dynamic_cast<VcWorkspace*>(&workspace);
  if (!ws) throw InputError("workspace", "", "not a VC workspace (use VcModel::make_workspace)");
  if (!ws->impl) ws->impl = std::make_unique<VcWorkspace::Impl>();
  const Impl& M = *impl_;
  VcWorkspace::Impl& W = *ws->impl;
  prepare_workspace(impl_, scene_.solver, W);
  if (M.multiple_shooting) return solve_multiple(*ws, warm_start);

  Solution sol;
  sol.model = "vc";
  SolverSummary& sum = sol.summary;
  sum.unknowns = 6;
  sum.integrator = W.shot_integrator->name();

  Eigen::VectorXd& x = W.x;
  Vec6 guess;
  bool warm = false;
  if (warm_start && warm_reaction(*warm_start, guess)) {
    x = guess;
    warm = true;
  } else if (warm_start && warm_start->unknowns.size() == 6 && warm_start->unknowns.allFinite()) {
    x = warm_start->unknowns;
    warm = true;
  } else {
    x = initial_guess(options_.initial_guess);
  }

  ShootingSystem system(M, W);
  bvp::NewtonOptions nopt = bvp::NewtonOptions::from(scene_.solver);
  // By global equilibrium |n(0)| <= F_s and |m(0)| <~ M_s: the solution lies within a scaled
  // distance of about sqrt(6) of the origin. Longer Newton steps only overshoot into strongly
  // coiled shapes (where RK4 fails or a wrong equilibrium waits), so bound them.
  nopt.max_newton_step = kMaxNewtonStep;
  set_lambda(M, W, 1.0);
  bvp::NewtonResult res = W.newton.solve(system, x, nopt);
  detail::copy_newton_result(res, sum);
  if (!res.converged() && !warm && nopt.max_iterations > sum.iterations) {
    // A cold start failed: retry once from the other straight-robot guess (the equilibrium guess
    // overestimates the lever of tip forces on strongly bent robots, zeros ignore the tendons).
    const VcInitialGuess other = options_.initial_guess == VcInitialGuess::Equilibrium ? VcInitialGuess::Zero
                                                                                      : VcInitialGuess::Equilibrium;
    Eigen::VectorXd xr = initial_guess(other);
    bvp::NewtonOptions ropt = nopt;
    ropt.max_iterations = nopt.max_iterations - sum.iterations;
    const std::string first = sum.message;
    res = W.newton.solve(system, xr, ropt);
    detail::copy_newton_result(res, sum);
    if (res.converged()) {
      x = xr;
      sum.message += " (retry from the other initial guess; first attempt: " + first + ")";
    } else {
      sum.message += "; first attempt: " + first;
    }
  }

  if (!res.converged() && scene_.solver.continuation) {
    // Load continuation from the unloaded robot, where n = m = 0 is exact (load_continuation.hpp).
    x.setZero();
    detail::continue_loads(W.newton, system, x, nopt, scene_.solver, sum);
  }

  // Final pass at the returned unknowns: frames, samples, tendon lengths.
  const Vec6 xs = x;
  sol.unknowns = x;
  sol.tensions = M.tensions;
  sol.disk_frames.reserve(M.routing.disk_count());
  sol.backbone.reserve(M.routing.disk_count());
  const int nseg = static_cast<int>(scene_.robot.segments.size());
  std::vector<double> seg_lengths(static_cast<std::size_t>(nseg) * M.tendon_count, 0.0);
  Record rec{&sol.disk_frames, &sol.backbone, &seg_lengths};
  bvp::Integrator& fin = M.lengths_in_shots ? *W.shot_integrator : *W.final_integrator;
  RodOde& final_rod = *W.final_rod;
  Vec6 r;
  const bool integrated = shoot_impl(M, W.loads, fin, final_rod, W.y.data(), xs, r, &rec);
  if (!integrated) {
    sol.disk_frames.clear();
    sol.backbone.clear();
    if (sum.converged()) {
      sum.termination = TerminationType::IntegrationFailed;
      sum.message += "; the final pass at the solution failed to integrate";
    }
  } else {
    // Tendon displacements from the integrated lengths (Eq. 56).
    const bool per_segment = scene_.actuation.convention == Actuation::DisplacementConvention::PerSegment;
    sol.tendon_displacements.assign(M.tendon_count, 0.0);
    for (const RoutedTendon& t : M.routing.tendons) {
      const double len_end = seg_lengths[t.segment * M.tendon_count + t.index];
      double straight = M.routing.disk_s[t.end_disk];
      double len = len_end;
      if (per_segment && t.segment > 0) {
        straight -= M.routing.segment_end_s[t.segment - 1];
        len -= seg_lengths[(t.segment - 1) * M.tendon_count + t.index];
      }
      sol.tendon_displacements[t.index] = straight - len;
    }
    // The converged flag must describe the reported shape: recheck its residual.
    if (sum.converged()) {
      const double scaled =
          std::max(r.head<3>().cwiseAbs().maxCoeff() / M.force_scale, r.tail<3>().cwiseAbs().maxCoeff() / M.moment_scale);
      if (!(scaled <= scene_.solver.function_tolerance)) {
        sum.termination = TerminationType::NoConvergence;
        sum.message += "; final pass residual " + format_value(scaled) + " above tolerance";
        sum.residual_norm = scaled;
        sum.physical_residual = r.norm();
      }
    }
  }
  sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sol;
}

Solution VcModel::solve_multiple(VcWorkspace& ws, const Solution* warm_start) const {
  const auto t0 = std::chrono::steady_clock::now();
  const Impl& M = *impl_;
  VcWorkspace::Impl& W = *ws.impl;
  set_lambda(M, W, 1.0);  // sizes W.loads, which the interval ODEs point into
  prepare_multiple_shooting(M, W);
  bvp::ParameterizedSystem& system = *W.ms_system;
  const int N = static_cast<int>(M.interval_segment.size());
  const int dim = cosserat::kStateSize;
  const int size = dim * N;

  Solution sol;
  sol.model = "vc";
  SolverSummary& sum = sol.summary;
  sum.unknowns = size;
  sum.integrator = W.shot_integrator->name();

  // Initial guess: a previous multiple-shooting solution, else the disk states of any previous
  // solution (its backbone samples, also those of a single-shooting solve), else the straight
  // robot's statics.
  Eigen::VectorXd x(size);
  bool warm = false;
  if (warm_start && warm_start->unknowns.size() == size && warm_start->unknowns.allFinite()) {
    x = warm_start->unknowns;
    warm = true;
  } else if (warm_start && static_cast<int>(warm_start->backbone.size()) == M.routing.disk_count()) {
    for (int k = 0; k < N; ++k) {
      const BackboneSample& b = warm_start->backbone[k];
      double* y = x.data() + static_cast<long>(k) * dim;
      cosserat::position(y) = b.frame.p;
      cosserat::rotation(y) = b.frame.R;
      cosserat::force(y) = b.n;
      cosserat::moment(y) = b.m;
    }
    warm = x.allFinite();
  }
  if (!warm) straight_node_states(M, 1.0, x);

  set_lambda(M, W, 1.0);
  const bvp::NewtonOptions nopt = bvp::NewtonOptions::from(scene_.solver);
  const double first_step = options_.multiple_shooting_threshold / std::max(M.tension_parameter, 1e-300);
  if (!warm && scene_.solver.continuation) {
    // Cold: load the robot from rest. A direct Newton solve from the straight robot lands on
    // other (coiled, buckled) equilibria when the loads bend it strongly (vc.hpp).
    straight_node_states(M, 0.0, x);
    detail::continue_loads(W.newton, system, x, nopt, scene_.solver, sum, first_step,
                           "multiple shooting, loaded from rest");
  } else {
    bvp::NewtonResult res = W.newton.solve(system, x, nopt);
    detail::copy_newton_result(res, sum);
    if (!res.converged() && scene_.solver.continuation) {
      const std::string direct = sum.message;
      straight_node_states(M, 0.0, x);
      detail::continue_loads(W.newton, system, x, nopt, scene_.solver, sum, first_step,
                           "multiple shooting, loaded from rest");
      sum.message += "; the warm-started direct solve failed: " + direct;
    }
  }
  set_lambda(M, W, 1.0);  // the final pass reports the full load's residual

  // Final pass: every interval from its own start state (a sweep from the base would amplify
  // the errors multiple shooting avoids), recording frames, samples and tendon lengths.
  sol.unknowns = x;
  sol.tensions = M.tensions;
  sol.disk_frames.reserve(M.routing.disk_count());
  sol.backbone.reserve(M.routing.disk_count());
  sol.disk_frames.push_back(Frame{});
  sol.backbone.push_back(BackboneSample{0.0, Frame{}, Vec3(x.segment<3>(12)), Vec3(x.segment<3>(15))});
  const int nseg = static_cast<int>(scene_.robot.segments.size());
  const int K = M.tendon_count;
  std::vector<double> seg_lengths(static_cast<std::size_t>(nseg) * K, 0.0), cum(K, 0.0);
  bvp::Integrator& fin = M.lengths_in_shots ? *W.shot_integrator : *W.final_integrator;
  RodOde& rod = *W.final_rod;
  double* y = W.y.data();
  bool integrated = true;
  for (int k = 0; k < N && integrated; ++k) {
    const int i = M.interval_segment[k];
    std::copy(x.data() + static_cast<long>(k) * dim, x.data() + static_cast<long>(k + 1) * dim, y);
    for (int t = 0; t < K; ++t) y[dim + t] = 0.0;
    rod.set(&W.loads.segments[i], &W.loads.weight);
    integrated = fin.integrate(rod, M.routing.disk_s[k], M.routing.disk_s[k + 1], y) &&
                 disk_point_loads(M, W.loads, i, k + 1, y) && Eigen::Map<const Eigen::VectorXd>(y, dim + K).allFinite();
    if (!integrated) break;
    for (int t = 0; t < K; ++t) cum[t] += y[dim + t];
    const Frame f = cosserat::frame_of(y);
    sol.disk_frames.push_back(f);
    sol.backbone.push_back(
        BackboneSample{M.routing.disk_s[k + 1], f, Vec3(cosserat::force(y)), Vec3(cosserat::moment(y))});
    if (k + 1 == M.routing.segment_end_disk[i])
      for (int t = 0; t < K; ++t) seg_lengths[static_cast<std::size_t>(i) * K + t] = cum[t];
  }
  if (!integrated) {
    sol.disk_frames.clear();
    sol.backbone.clear();
    if (sum.converged()) {
      sum.termination = TerminationType::IntegrationFailed;
      sum.message += "; the final pass at the solution failed to integrate";
    }
  } else {
    const bool per_segment = scene_.actuation.convention == Actuation::DisplacementConvention::PerSegment;
    sol.tendon_displacements.assign(K, 0.0);
    for (const RoutedTendon& t : M.routing.tendons) {
      double straight = M.routing.disk_s[t.end_disk];
      double len = seg_lengths[t.segment * K + t.index];
      if (per_segment && t.segment > 0) {
        straight -= M.routing.segment_end_s[t.segment - 1];
        len -= seg_lengths[(t.segment - 1) * K + t.index];
      }
      sol.tendon_displacements[t.index] = straight - len;
    }
    if (sum.converged()) {
      // The converged flag must describe the reported unknowns: recheck their residual.
      Eigen::VectorXd f(size), sc(size);
      system.residual_scale(sc);
      const bool ok = system.residual(x, f);
      const double scaled = ok ? f.cwiseProduct(sc).cwiseAbs().maxCoeff() : std::numeric_limits<double>::infinity();
      if (!(scaled <= scene_.solver.function_tolerance)) {
        sum.termination = TerminationType::NoConvergence;
        sum.message += "; final residual " + format_value(scaled) + " above tolerance";
        sum.residual_norm = scaled;
      }
    }
  }
  sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sol;
}

namespace detail {
std::unique_ptr<LegacyStaticModel> make_legacy_vc_model(const Scene& scene) { return std::make_unique<VcModel>(scene); }
}  // namespace detail

}  // namespace tdcr
