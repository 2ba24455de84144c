// What VC's two formulations share: the bound loads, the disk point loads, a shot from the base
// and the tendon displacements (vc_shooting.hpp).
#include "vc/vc_shooting.hpp"

#include <type_traits>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/LU>

#include "solve/bvp_options.hpp"
#include "solve/stability_mesh.hpp"
#include "physics/geometry_check.hpp"
#include "physics/tendon_path.hpp"
#include "vc/vc_friction.hpp"

namespace tdcr {

VcWorkspace::Impl::Impl(const VcModel& model)
    : segments(model.robot().segments.size()), tendon_count(static_cast<int>(model.routing().tendons.size())) {}

VcWorkspace::Impl::~Impl() = default;

namespace vc {

/// Fixed-point iteration while it contracts (its factor is about
/// T r^2 / (EI |q_k|), small for moderate bends); once it stops contracting (a strong tendon
/// continuing past a large point load on a strongly bent robot: the factor passes 1 and the
/// iteration falls into a 2-cycle), Newton on h(z) = z - G(z) from the start with a
/// forward-difference Jacobian, each step backtracked until the scaled |h| decreases. Without the
/// backtracking Newton fell into 2-cycles of its own where the root exists (1393 failed kinks
/// at disk 5 of s1135, draw 135 beyond the loaded suite, stalled VC's damped snap). Where no root
/// exists (the kink would put a continuing tendon past its geometric limit just distal of the
/// disk, where t_k+ = q_k+ / |q_k+| flips), the backtracking ends on |h| > 0 at that limit:
/// false, never a success.
bool kink_fixed_point(const KinkMap<double>& G, double force_scale, double moment_scale, Vec6& z) {
  Vec6 scale;
  scale << Vec3::Constant(force_scale), Vec3::Constant(moment_scale);
  const Vec6 start = z;
  double previous = INFINITY;
  for (int it = 0; it < 100; ++it) {
    const Vec6 next = G(z);
    const double step = (next - z).cwiseQuotient(scale).cwiseAbs().maxCoeff();
    z = next;
    if (step <= 1e-15) return z.allFinite();
    if (!(step < 0.9 * previous)) break;
    previous = step;
  }
  z = start;
  Vec6 h = z - G(z);
  for (int it = 0; it < 30; ++it) {
    Eigen::Matrix<double, 6, 6> J;
    for (int c = 0; c < 6; ++c) {
      Vec6 zc = z;
      const double d = 1e-7 * std::max(std::abs(z[c]), scale[c]);
      zc[c] += d;
      J.col(c) = (zc - G(zc) - h) / d;
    }
    const Vec6 dz = J.partialPivLu().solve(-h);
    if (!dz.allFinite()) return false;
    if (dz.cwiseQuotient(scale).cwiseAbs().maxCoeff() <= 1e-14) {
      z += dz;
      return z.allFinite();
    }
    const double norm = h.cwiseQuotient(scale).norm();
    double a = 1.0;
    for (int halvings = 0;; ++halvings) {
      const Vec6 zn = z + a * dz;
      const Vec6 hn = zn - G(zn);
      if (hn.allFinite() && hn.cwiseQuotient(scale).norm() <= (1.0 - 1e-4 * a) * norm) {
        z = zn;
        h = hn;
        break;
      }
      if (halvings == 30) return false;  // no decrease along the Newton direction: no root here
      a *= 0.5;
    }
  }
  return false;
}

namespace {

bool same_integration(const SolverOptions& a, const SolverOptions& b) {
  return a.integrator == b.integrator && a.rk4_steps == b.rk4_steps && a.rk4_max_step == b.rk4_max_step &&
         a.cvode_rtol == b.cvode_rtol && a.cvode_atol == b.cvode_atol;
}

}  // namespace

void bind_input(VcWorkspace::Impl& W, const VcModel& model, const ModelInput& input, const SolverOptions& options) {
  const Robot& robot = model.robot();
  const TendonRouting& rt = model.routing();
  W.model = &model;
  ++W.loads_version;
  W.loads.bind(robot, rt, input);
  W.lambda = 1.0;
  W.per_segment = input.actuation.convention == Actuation::DisplacementConvention::PerSegment;
  W.section = cosserat::Section::from(robot, model.effects(), W.loads.backbone_weight());
  W.contacts.clear();
  W.obstacles = input.environment.obstacles;  // allocates only when the obstacles grow
  if (!W.obstacles.empty()) {
    const int N = robot.total_disks();
    W.surfaces.backbone_radius = robot.backbone.outer_radius;
    W.surfaces.disk_radius.assign(static_cast<std::size_t>(N + 1), 0.0);
    for (int j = 0; j <= N; ++j) W.surfaces.disk_radius[static_cast<std::size_t>(j)] = robot.segments[rt.disk_segment[j]].disk_radius;
    const double L = robot.total_length();
    W.law = contact::Law{};
    W.law.stiffness = input.environment.contact.stiffness;
    W.law.force_scale = 1.0 / (W.section.inv_kbt.x() * L * L);  // EI / L^2
    W.law.length_scale = W.surfaces.backbone_radius > 0.0 ? W.surfaces.backbone_radius : 1e-3 * L;
  }
  for (SegmentLoads& s : W.segments) {
    s.tendons.clear();
    s.tendon_index.clear();
    s.terminating.clear();
    s.terminating_index.clear();
    s.lengths.clear();
    s.routed.clear();
    s.terminating_routed.clear();
    s.all_straight = true;
  }
  for (const RoutedTendon& t : rt.tendons) {
    const double T = W.loads.tension(t.index);
    const cosserat::TendonLoad load = cosserat::TendonLoad::make(physics::tendon_offset(t, 0.0), T);
    for (int i = 0; i <= t.segment; ++i) {
      SegmentLoads& s = W.segments[i];
      s.lengths.push_back(LengthTerm{load.r, t.index, &t});
      s.all_straight = s.all_straight && t.straight();
      if (T > 0.0) {
        s.tendons.push_back(load);
        s.tendon_index.push_back(t.index);
        s.routed.push_back(&t);
      }
    }
    if (T > 0.0) {
      W.segments[t.segment].terminating.push_back(load);
      W.segments[t.segment].terminating_index.push_back(t.index);
      W.segments[t.segment].terminating_routed.push_back(&t);
    }
  }
  for (SegmentLoads& s : W.segments) {
    s.at_s.resize(s.tendons.size());
    s.terminating_at_s.resize(s.terminating.size());
  }

  detail::update_stability_integrator(options, W.stability_integrator);
  if (W.shot_integrator && same_integration(W.integration, options)) return;
  if (W.shot_integrator && is_rk4(W.integration.integrator) && is_rk4(options.integrator)) {
    // Only the RK4 mesh changes (e.g. an accuracy-driven refinement, SolverOptions::
    // tip_tolerance): refine the integrators in place, so that the formulations, and the
    // Jacobian their Newton solver holds factored, survive for the warm-started re-solve.
    static_cast<bvp::Rk4Integrator&>(*W.shot_integrator).set_mesh(options.rk4_steps, options.rk4_max_step);
    static_cast<bvp::Rk4Integrator&>(*W.final_integrator).set_mesh(options.rk4_steps, options.rk4_max_step);
    W.integration = options;
    ++W.loads_version;  // the memoised last shot belongs to the old mesh
    return;
  }
  // New integration settings: new integrators, and the rods and formulations that use them.
  if (W.shot_integrator) W.retired_rhs += W.shot_integrator->rhs_evaluations();
  if (W.final_integrator) W.retired_rhs += W.final_integrator->rhs_evaluations();
  W.integration = options;
  W.shot_integrator = bvp::make_integrator(detail::integrator_options(options));
  const bool lengths_in_shots = options.integrator == IntegratorKind::Cvode;
  W.final_integrator = lengths_in_shots ? nullptr : bvp::make_integrator(detail::integrator_options(options));
  W.shot_rod = std::make_unique<TendonRod>(W.section, W.segments[0], W.tendon_count, lengths_in_shots);
  W.final_rod = std::make_unique<TendonRod>(W.section, W.segments[0], W.tendon_count, true);
  W.final_rod->watch(&W.degeneracy);
  W.friction = model.effects().tendon_friction.on();
  if (W.friction) {
    const TendonFriction& f = model.effects().tendon_friction;
    W.friction_shot_rod = std::make_unique<FrictionRod>(W.section, W.segments[0], f, W.tendon_count, lengths_in_shots);
    W.friction_final_rod = std::make_unique<FrictionRod>(W.section, W.segments[0], f, W.tendon_count, true);
    W.friction_final_rod->watch(&W.degeneracy);
  }
  W.y = Eigen::VectorXd::Zero(cosserat::kStateSize + (W.friction ? 2 : 1) * W.tendon_count);
  W.segment_lengths.assign(W.segments.size() * W.tendon_count, 0.0);
  W.single.reset();
  W.multiple.reset();
}

void set_driven_tensions(VcWorkspace::Impl& W, const std::vector<int>& index, const Eigen::VectorXd& T) {
  for (std::size_t i = 0; i < index.size(); ++i) W.loads.set_fixed_tension(index[i], T[static_cast<Eigen::Index>(i)]);
  const double lambda = W.lambda;
  W.lambda = NAN;  // set_load_factor then refreshes the segments' tensions at the same factor
  set_load_factor(W, lambda);
}

void set_load_factor(VcWorkspace::Impl& W, double lambda) {
  if (W.lambda == lambda) return;
  W.loads.set_load_factor(lambda);
  W.section.weight = W.loads.backbone_weight();
  for (SegmentLoads& s : W.segments) {
    for (std::size_t k = 0; k < s.tendons.size(); ++k) s.tendons[k].T = W.loads.tension(s.tendon_index[k]);
    for (std::size_t k = 0; k < s.terminating.size(); ++k)
      s.terminating[k].T = W.loads.tension(s.terminating_index[k]);
  }
  W.lambda = lambda;
  ++W.loads_version;
}

namespace {

/// The kinks' fixed point in double (kink_fixed_point).
bool solve_kinks(const KinkMap<double>& G, double force_scale, double moment_scale, Vec6& z) {
  return kink_fixed_point(G, force_scale, moment_scale, z);
}

/// The kinks' fixed point with its derivative: the value by kink_fixed_point, the derivative
/// implicitly, dz = (I - dG/dz)^-1 (dG/dp dp), exact at the fixed point.
bool solve_kinks(const KinkMap<Dual>& G, double force_scale, double moment_scale, Vec6T<Dual>& z) {
  const auto value = [](const Dual& d) { return d.v; };
  const auto constant = [](double d) { return Dual(d); };
  const Mat3 R = G.R.unaryExpr(value);
  const Vec3 u = G.u.unaryExpr(value), v = G.v.unaryExpr(value);
  Vec6 zv = z.unaryExpr(value);
  if (!kink_fixed_point(KinkMap<double>{G.S, R, u, v, G.tendons, G.base.unaryExpr(value)}, force_scale,
                        moment_scale, zv))
    return false;
  // dG/dp dp: G at the (constant) fixed point with the inputs' derivatives.
  const Vec6T<Dual> gp = G(zv.unaryExpr(constant));
  // dG/dz: G with constant inputs and z seeded with the identity.
  Vec6T<Dual> zs;
  for (int c = 0; c < 6; ++c) zs[c] = Dual::variable(zv[c], c);
  const KinkMap<Dual> Gc{G.S, R.unaryExpr(constant), u.unaryExpr(constant), v.unaryExpr(constant), G.tendons,
                         G.base.unaryExpr(value).unaryExpr(constant)};
  const Vec6T<Dual> gz = Gc(zs);
  Mat6 A, B;
  for (int r = 0; r < 6; ++r) {
    A.row(r) = -gz[r].derivatives().transpose();
    B.row(r) = gp[r].derivatives().transpose();
  }
  A.diagonal().array() += 1.0;
  const Mat6 dz = A.partialPivLu().solve(B);
  if (!dz.allFinite()) return false;
  for (int r = 0; r < 6; ++r) {
    z[r].v = zv[r];
    for (int k = 0; k < 6; ++k) z[r].d[k] = dz(r, k);
  }
  return true;
}

}  // namespace

template <typename T>
bool disk_point_loads(const VcWorkspace::Impl& W, int i, int j, T* y) {
  using V3 = Vec3T<T>;
  const TendonRouting& rt = W.model->routing();
  const cosserat::Section& S = W.section;
  const int nseg = static_cast<int>(W.segments.size());
  const SegmentLoads& seg = W.segments[i];
  const int last = rt.segment_end_disk[i];
  const bool terminates = j == last && !seg.terminating.empty();
  const bool weighted = W.loads.has_disk_weight() && W.loads.disk_weight(j).squaredNorm() > 0.0;
  // Contact forces (double only: with candidates the Jacobian is taken by differences).
  bool touched = false;
  if constexpr (std::is_same_v<T, double>)
    for (const contact::Candidate& c : W.contacts) touched = touched || c.disk == j;
  if (!terminates && !weighted && !touched) return true;
  const double s = rt.disk_s[j];
  // Point loads at disk j, with u, v just proximal of it.
  const Mat3T<T> R = Eigen::Map<const Mat3T<T>>(y + 3);
  Eigen::Map<V3> n(y + 12), m(y + 15);
  const V3 u = cosserat::detail::curvature<T>(S, R, m);
  const V3 v = cosserat::detail::strain<T>(S, R, n);
  if (terminates) {
    // Eq. 40-41: tendon termination forces F_k = -T_k R t_k at p + R r_k.
    V3 dn = V3::Zero(), dm = V3::Zero();
    for (const cosserat::TendonLoad& t : seg.terminating_at(s)) {
      const V3 q = cosserat::detail::tangent(v, u, t);
      const V3 F = -(t.T / q.norm()) * (R * q);
      dn += F;
      dm += (R * t.r).cross(F);
    }
    n -= dn;
    m -= dm;
  }
  if (weighted) n -= W.loads.disk_weight(j);
  if constexpr (std::is_same_v<T, double>) {
    if (touched) {
      const Frame frame = cosserat::frame_of(y);
      for (const contact::Candidate& c : W.contacts) {
        if (c.disk != j) continue;
        const ContactPoint at =
            contact_point(W.obstacles[c.obstacle], frame, c.body, W.surfaces.radius(c.disk, c.body));
        const Vec3 f = (c.lambda * W.law.force_scale) * at.normal;
        n -= f;
        m -= (at.point - frame.p).cross(f);
      }
    }
  }
  // Kinks: the point loads make u, v jump, so every tensioned tendon continuing past disk j
  // changes direction there and pulls on the backbone with T_k R (t_k+ - t_k-) at p + R r_k.
  // t_k+ depends on the wrench after the kink: a fixed point z = G(z) (kink_fixed_point).
  const std::vector<cosserat::TendonLoad>* cont = nullptr;
  if (j < last)
    cont = &seg.tendons_at(s);
  else if (i + 1 < nseg)
    cont = &W.segments[i + 1].tendons_at(s);
  if (!W.model->options().kink_forces || !cont || cont->empty()) return true;
  Vec6T<T> z;
  z << n, m;
  const KinkMap<T> G{S, R, u, v, *cont, z};
  if (!solve_kinks(G, W.loads.force_scale(), W.loads.moment_scale(), z)) return false;
  n = z.template head<3>();
  m = z.template tail<3>();
  return true;
}

template bool disk_point_loads<double>(const VcWorkspace::Impl&, int, int, double*);
template bool disk_point_loads<Dual>(const VcWorkspace::Impl&, int, int, Dual*);

namespace {

// What a shot does besides the rod's integration, without friction (nothing) or with it
// (vc_friction.hpp: the tension states).
bool has_lengths(const TendonRod& rod) { return rod.dimension() > cosserat::kStateSize; }
bool has_lengths(const FrictionRod& rod) { return rod.lengths(); }
void begin(const VcWorkspace::Impl&, const TendonRod&, double*) {}
void begin(const VcWorkspace::Impl& W, const FrictionRod& rod, double* y) { begin_friction_shot(W, rod, y); }
void at_disk(VcWorkspace::Impl&, const TendonRod&, int, int, const double*) {}
void at_disk(VcWorkspace::Impl& W, const FrictionRod& rod, int i, int j, const double* y) {
  friction_at_disk(W, rod, i, j, y);
}
void end(const VcWorkspace::Impl&, const TendonRod&, const double*, const Record&) {}
void end(const VcWorkspace::Impl& W, const FrictionRod& rod, const double* y, const Record& rec) {
  if (rec.end_tensions) friction_end_tensions(W, rod, y, *rec.end_tensions);
}

}  // namespace

template <class Rod>
bool shoot(VcWorkspace::Impl& W, bvp::Integrator& integ, Rod& rod, const Vec6& x, Vec6& res, const Record* rec,
           const Frame* base) {
  double* y = W.y.data();
  const int dim = rod.dimension();
  for (int i = 0; i < dim; ++i) y[i] = 0.0;
  const Frame f0 = base ? *base : Frame{};
  cosserat::position(y) = f0.p;
  cosserat::rotation(y) = f0.R;
  cosserat::force(y) = x.head<3>();
  cosserat::moment(y) = x.tail<3>();
  begin(W, rod, y);
  const TendonRouting& rt = W.model->routing();
  if (rec) {
    rec->frames->push_back(f0);
    rec->samples->push_back(BackboneSample{0.0, f0, x.head<3>(), x.tail<3>()});
  }
  const int nseg = static_cast<int>(W.segments.size());
  const int K = W.tendon_count;
  for (int i = 0; i < nseg; ++i) {
    rod.set(W.segments[i]);
    const int last = rt.segment_end_disk[i];
    const int first = i == 0 ? 1 : rt.segment_end_disk[i - 1] + 1;
    for (int j = first; j <= last; ++j) {
      if (!integ.integrate(rod, rt.disk_s[j - 1], rt.disk_s[j], y)) return false;
      at_disk(W, rod, i, j, y);
      if (!disk_point_loads(W, i, j, y)) return false;
      if (rec) {
        const Frame f = cosserat::frame_of(y);
        rec->frames->push_back(f);
        rec->samples->push_back(BackboneSample{rt.disk_s[j], f, Vec3(cosserat::force(y)), Vec3(cosserat::moment(y))});
      }
    }
    if (rec && rec->segment_end_lengths && has_lengths(rod))
      for (int k = 0; k < K; ++k) (*rec->segment_end_lengths)[i * K + k] = y[cosserat::kStateSize + k];
  }
  if (rec) end(W, rod, y, *rec);
  res.head<3>() = cosserat::force(y);
  res.tail<3>() = cosserat::moment(y);
  if (W.loads.has_tip_wrench()) {
    res.head<3>() -= W.loads.tip_force();
    res.tail<3>() -= W.loads.tip_moment();
  }
  return res.allFinite();
}

template bool shoot<TendonRod>(VcWorkspace::Impl&, bvp::Integrator&, TendonRod&, const Vec6&, Vec6&, const Record*,
                               const Frame*);
template bool shoot<FrictionRod>(VcWorkspace::Impl&, bvp::Integrator&, FrictionRod&, const Vec6&, Vec6&,
                                 const Record*, const Frame*);

bool shoot(VcWorkspace::Impl& W, bool final, const Vec6& x, Vec6& res, const Record* rec) {
  bvp::Integrator& integ = final ? W.final_pass_integrator() : *W.shot_integrator;
  if (W.friction) return shoot(W, integ, final ? *W.friction_final_rod : *W.friction_shot_rod, x, res, rec);
  return shoot(W, integ, final ? *W.final_rod : *W.shot_rod, x, res, rec);
}

bool tendon_limit(const VcWorkspace::Impl& W, double threshold, std::string& why) {
  const Degeneracy& d = W.degeneracy;
  if (d.tendon < 0 || !(d.value >= threshold)) return false;
  char where[48];
  std::snprintf(where, sizeof where, "at s = %.4g m", d.s);
  why = physics::tendon_limit_message(d.tendon, d.value, where);
  return true;
}

void tendon_displacements(const VcWorkspace::Impl& W, const std::vector<double>& lengths,
                          std::vector<double>& displacements) {
  const TendonRouting& rt = W.model->routing();
  const int K = W.tendon_count;
  displacements.assign(K, 0.0);
  for (const RoutedTendon& t : rt.tendons) {
    // The length of the path on the straight robot (the disks' arc length for straight routing).
    double s0 = 0.0;
    double len = lengths[t.segment * K + t.index];
    if (W.per_segment && t.segment > 0) {
      s0 = rt.segment_end_s[t.segment - 1];
      len -= lengths[(t.segment - 1) * K + t.index];
    }
    const double rest = t.straight() ? rt.disk_s[t.end_disk] - s0 : physics::rest_length(t, s0, rt.disk_s[t.end_disk]);
    displacements[t.index] = rest - len;
  }
}

}  // namespace vc

}  // namespace tdcr
