// The fixed mesh, one shot of a time step, the reconstruction of a shape from its strains and
// its energies (vc_dynamics_mesh.hpp).
#include "vc/vc_dynamics_mesh.hpp"

#include <algorithm>
#include <cmath>

#include "physics/cosserat_rhs.hpp"
#include "physics/tendon_path.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr::vc::dyn {

void Mesh::build(const VcWorkspace::Impl& W, int rk4_steps, double rk4_max_step) {
  const TendonRouting& rt = W.model->routing();
  const Robot& robot = W.model->robot();
  const int nd = rt.disk_count();
  intervals.clear();
  pre.assign(nd, -1);
  post.assign(nd, -1);
  disk_mass.assign(nd, 0.0);
  disk_inertia.assign(nd, Vec3::Zero());
  double hole_radius = 0.0;
  for (const RoutedTendon& t : rt.tendons) hole_radius = std::max(hole_radius, physics::max_offset(t));
  weight.clear();
  int p = 0;
  for (int j = 1; j < nd; ++j) {
    Interval I;
    I.segment = rt.disk_segment[j];
    I.disk = j;
    I.s0 = rt.disk_s[j - 1];
    const double len = rt.disk_s[j] - I.s0;
    I.steps = std::max(rk4_steps, static_cast<int>(std::ceil(len / rk4_max_step - 1e-12)));
    I.h = len / I.steps;
    I.first = p;
    for (int k = 0; k < I.steps; ++k)
      for (const double c : {1.0, 2.0, 2.0, 1.0}) weight.push_back(c * I.h / 6.0);
    p += 4 * I.steps;
    pre[j] = p++;
    post[j] = p++;
    weight.push_back(0.0);
    weight.push_back(0.0);
    const Segment& seg = robot.segments[I.segment];
    disk_mass[j] = seg.disk_mass;
    const double r = seg.disk_radius > 0.0 ? seg.disk_radius : hole_radius;
    disk_inertia[j] = seg.disk_mass * r * r * Vec3(0.25, 0.25, 0.5);
    intervals.push_back(I);
  }
  points = p;
}

// As vc::disk_point_loads does for the statics: tendon terminations (Eq. 40-41), the disk's
// weight, and the kinks of the continuing tendons (VcOptions::kink_forces); here also the disk's
// inertia (its mass and its rotary inertia), and the step's strain law on both sides.
bool disk_loads(VcWorkspace::Impl& W, const ShotData& d, int i, int j, double* y) {
  const Mesh& M = *d.mesh;
  const StepSection& X = *d.X;
  const TendonRouting& rt = W.model->routing();
  const SegmentLoads& seg = W.segments[i];
  const int nseg = static_cast<int>(W.segments.size());
  const int last = rt.segment_end_disk[i];
  const double s = rt.disk_s[j];
  const Eigen::Map<const Mat3> R(y + 3);
  Eigen::Map<Vec3> n(y + 12), m(y + 15);
  const Eigen::Map<const Vec3> q(y + 18), w(y + 21);
  const Values& hp = (*d.history)[M.pre[j]];
  Vec3 v, u;
  X.strains(R, n, m, hp, v, u);
  Values& vp = (*d.values)[M.pre[j]];
  vp << v, u, q, w, Vec6::Zero();
  const bool terminates = d.distributed && j == last && !seg.terminating.empty();
  const bool weighted = W.loads.has_disk_weight() && W.loads.disk_weight(j).squaredNorm() > 0.0;
  const bool massive = M.disk_mass[j] > 0.0 && (X.c0 != 0.0 || hp.segment<3>(kQ).squaredNorm() > 0.0 ||
                                               hp.segment<3>(kW).squaredNorm() > 0.0);
  if (terminates) {
    for (const cosserat::TendonLoad& t : seg.terminating_at(s)) {
      const Vec3 qk = v + u.cross(t.r) + t.dr;
      const Vec3 F = -(t.T / qk.norm()) * (R * qk);
      n -= F;
      m -= (R * t.r).cross(F);
    }
  }
  if (weighted) n -= W.loads.disk_weight(j);
  // The disk moves with the backbone point as a rigid body: n jumps by m_d a, a = R (w x q + q_t),
  // m by the rate of its angular momentum R (J_d w_t + w x J_d w) (body frame: w, J_d diagonal).
  if (massive) {
    n += M.disk_mass[j] * (R * (w.cross(q) + X.c0 * q + hp.segment<3>(kQ)));
    const Vec3& J = M.disk_inertia[j];
    m += R * (J.cwiseProduct(X.c0 * w + hp.segment<3>(kW)) + w.cross(J.cwiseProduct(w)));
  }
  const Values& hd = (*d.history)[M.post[j]];
  if (terminates || weighted || massive) {
    const std::vector<cosserat::TendonLoad>* cont = nullptr;
    if (j < last)
      cont = &seg.tendons_at(s);
    else if (i + 1 < nseg)
      cont = &W.segments[i + 1].tendons_at(s);
    if (d.distributed && W.model->options().kink_forces && cont && !cont->empty()) {
      // KinkMap's strain law is the static one with Seff; the step's law is that law at the
      // wrench shifted by the distal point's history (StepSection::shift).
      Vec3 zn, zm;
      X.shift(hd, zn, zm);
      const Vec3 Rzn = R * zn, Rzm = R * zm;
      Vec6 z;
      z << n - Rzn, m - Rzm;
      const KinkMap<double> G{X.Seff, Mat3(R), u, v, *cont, z};
      if (!kink_fixed_point(G, W.loads.force_scale(), W.loads.moment_scale(), z)) return false;
      n = z.head<3>() + Rzn;
      m = z.tail<3>() + Rzm;
    }
  }
  X.strains(R, n, m, hd, v, u);
  Values& vd = (*d.values)[M.post[j]];
  vd << v, u, q, w, Vec6::Zero();
  return true;
}

bool integrate_interval(VcWorkspace::Impl& W, const ShotData& d, const Interval& I, State& y) {
  const StepSection& X = *d.X;
  const ValuesList& H = *d.history;
  ValuesList& out = *d.values;
  const SegmentLoads& seg = W.segments[I.segment];
  const bool routed = !seg.all_straight;
  const double h = I.h;
  State k1, k2, k3, k4, tmp;
  int p = I.first;
  for (int st = 0; st < I.steps; ++st, p += 4) {
    const double s = I.s0 + st * h;
    const auto eval = [&](double sa, const State& ya, State& k, int point) {
      if (!d.distributed) {
        rhs(X, nullptr, 0, false, H[point], ya.data(), k.data(), out[point]);
        return;
      }
      const std::vector<cosserat::TendonLoad>& L = seg.tendons_at(sa);
      rhs(X, L.data(), static_cast<int>(L.size()), routed, H[point], ya.data(), k.data(), out[point]);
    };
    eval(s, y, k1, p);
    tmp = y + (0.5 * h) * k1;
    eval(s + 0.5 * h, tmp, k2, p + 1);
    tmp = y + (0.5 * h) * k2;
    eval(s + 0.5 * h, tmp, k3, p + 2);
    tmp = y + h * k3;
    eval(s + h, tmp, k4, p + 3);
    y += (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  return y.allFinite();
}

bool shoot(VcWorkspace::Impl& W, const ShotData& d, const Vec6& x, Vec6& res) {
  State y = State::Zero();
  Eigen::Map<Mat3>(y.data() + 3).setIdentity();
  y.segment<6>(12) = x;
  for (const Interval& I : d.mesh->intervals) {
    if (!integrate_interval(W, d, I, y)) return false;
    if (!disk_loads(W, d, I.segment, I.disk, y.data())) return false;
    if (d.nodes && I.disk < static_cast<int>(d.mesh->intervals.size())) (*d.nodes)[I.disk - 1] = y;
  }
  res = y.segment<6>(12);
  if (W.loads.has_tip_wrench()) {
    res.head<3>() -= W.loads.tip_force();
    res.tail<3>() -= W.loads.tip_moment();
  }
  return res.allFinite();
}

void reconstruct(const Mesh& M, const ValuesList& values, std::vector<Frame>& frames, std::vector<Vec3>& points) {
  frames.assign(M.intervals.size() + 1, Frame{});
  points.assign(M.points, Vec3::Zero());
  Vec3 p = Vec3::Zero();
  Mat3 R = Mat3::Identity();
  for (std::size_t k = 0; k < M.intervals.size(); ++k) {
    const Interval& I = M.intervals[k];
    const double h = I.h;
    int i = I.first;
    for (int st = 0; st < I.steps; ++st, i += 4) {
      const auto v = [&](int o) { return values[i + o].segment<3>(kV); };
      const auto U = [&](int o) { return lie::hat(values[i + o].segment<3>(kU)); };
      points[i] = p;
      const Vec3 dp1 = R * v(0);
      const Mat3 dR1 = R * U(0);
      const Vec3 p2 = p + 0.5 * h * dp1;
      const Mat3 R2 = R + 0.5 * h * dR1;
      points[i + 1] = p2;
      const Vec3 dp2 = R2 * v(1);
      const Mat3 dR2 = R2 * U(1);
      const Vec3 p3 = p + 0.5 * h * dp2;
      const Mat3 R3 = R + 0.5 * h * dR2;
      points[i + 2] = p3;
      const Vec3 dp3 = R3 * v(2);
      const Mat3 dR3 = R3 * U(2);
      const Vec3 p4 = p + h * dp3;
      const Mat3 R4 = R + h * dR3;
      points[i + 3] = p4;
      const Vec3 dp4 = R4 * v(3);
      const Mat3 dR4 = R4 * U(3);
      p += (h / 6.0) * (dp1 + 2.0 * dp2 + 2.0 * dp3 + dp4);
      R += (h / 6.0) * (dR1 + 2.0 * dR2 + 2.0 * dR3 + dR4);
    }
    points[M.pre[I.disk]] = p;
    points[M.post[I.disk]] = p;
    frames[k + 1] = Frame{R, p};
  }
}

namespace {
/// Arc length of point i of interval I (its RK4 stage).
double point_s(const Interval& I, int i) {
  const int step = (i - I.first) / 4, stage = (i - I.first) % 4;
  return I.s0 + (step + (stage == 0 ? 0.0 : stage == 3 ? 1.0 : 0.5)) * I.h;
}
}  // namespace

void path_pulls(const VcWorkspace::Impl& W, const Mesh& M, const ValuesList& values, std::vector<double>& lengths,
                std::vector<double>& pulls) {
  const TendonRouting& rt = W.model->routing();
  const int K = W.tendon_count;
  const std::size_t nseg = W.segments.size();
  lengths.assign(nseg * static_cast<std::size_t>(K), 0.0);
  pulls.assign(static_cast<std::size_t>(K), 0.0);  // running lengths from the base
  for (const Interval& I : M.intervals) {
    const SegmentLoads& seg = W.segments[I.segment];
    for (int i = I.first; i < I.first + 4 * I.steps; ++i) {
      const Vec3 v = values[i].segment<3>(kV), u = values[i].segment<3>(kU);
      const double wgt = M.weight[i];
      if (seg.all_straight) {
        for (const LengthTerm& t : seg.lengths) pulls[t.index] += wgt * physics::tendon_tangent(v, u, t.r).norm();
      } else {
        const double s = point_s(I, i);
        for (const LengthTerm& t : seg.lengths) {
          const physics::TendonPoint p = physics::tendon_path(*t.tendon, s);
          pulls[t.index] += wgt * physics::tendon_tangent(v, u, p.r, p.dr).norm();
        }
      }
    }
    if (I.disk == rt.segment_end_disk[I.segment])
      for (int k = 0; k < K; ++k) lengths[static_cast<std::size_t>(I.segment * K + k)] = pulls[k];
  }
  tendon_displacements(W, lengths, pulls);
}

void energies(const VcWorkspace::Impl& W, bool chords, const StepSection& X, const Mesh& M, const ValuesList& values,
              const std::vector<Frame>& frames, const std::vector<Vec3>& points, double& kinetic, double& potential) {
  const cosserat::Section& S = X.S;
  kinetic = 0.0;
  potential = 0.0;
  for (const Interval& I : M.intervals) {
    const SegmentLoads& seg = W.segments[I.segment];
    for (int i = I.first; i < I.first + 4 * I.steps; ++i) {
      const Values& y = values[i];
      const double wgt = M.weight[i];
      const Vec3 q = y.segment<3>(kQ), w = y.segment<3>(kW), u = y.segment<3>(kU);
      Vec3 v = y.segment<3>(kV);
      kinetic += 0.5 * wgt * (X.rho_a * q.squaredNorm() + w.dot(X.rho_j.cwiseProduct(w)));
      double e = u.dot(S.kbt.cwiseProduct(u));
      if (S.shear_extension) {
        const Vec3 dv = v - Vec3::UnitZ();
        e += dv.dot(S.kse.cwiseProduct(dv));
      }
      potential += 0.5 * wgt * e;
      if (S.gravity) potential -= wgt * S.weight.dot(points[i]);
      // Constant tensions: T times the tendon's path length (the point's share of it).
      const double s = point_s(I, i);
      if (!chords)
        for (const cosserat::TendonLoad& t : seg.tendons_at(s))
          potential += wgt * t.T * (v + u.cross(t.r) + t.dr).norm();
    }
    const int j = I.disk;
    if (M.disk_mass[j] > 0.0) {
      const Vec3 w = values[M.pre[j]].segment<3>(kW);
      kinetic += 0.5 * M.disk_mass[j] * values[M.pre[j]].segment<3>(kQ).squaredNorm() +
                 0.5 * w.dot(M.disk_inertia[j].cwiseProduct(w));
    }
    if (W.loads.has_disk_weight()) potential -= W.loads.disk_weight(j).dot(frames[j].p);
  }
  if (chords) {
    const TendonRouting& rt = W.model->routing();
    for (const RoutedTendon& t : rt.tendons)
      if (W.loads.tension(t.index) > 0.0)
        potential += W.loads.tension(t.index) * tendon::chord_length(frames.data(), rt, t.index);
  }
  if (W.loads.has_tip_wrench()) potential -= W.loads.tip_force().dot(frames.back().p);
}

}  // namespace tdcr::vc::dyn
