#include "tdcr/models/verification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tdcr/core/robot.hpp"
#include "tdcr/models/cosserat_rod.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

double EquilibriumCheck::relative_error() const {
  if (!evaluated) return std::numeric_limits<double>::infinity();
  const double f = force_scale > 0.0 ? force.norm() / force_scale : force.norm();
  const double m = moment_scale > 0.0 ? moment.norm() / moment_scale : moment.norm();
  return std::max(f, m);
}

EquilibriumCheck verify_equilibrium(const Scene& scene, const Solution& sol) {
  EquilibriumCheck c;
  const bool vc = sol.model == "vc", vcref = sol.model == "vcref";
  if (!vc && !vcref) {
    c.reason = "model '" + sol.model +
               "' reports no internal wrench at the base; check its own residual (summary) instead";
    return c;
  }
  const TendonRouting rt = TendonRouting::from(scene.robot);
  const int N = rt.disk_count() - 1;
  if (static_cast<int>(sol.disk_frames.size()) != N + 1) {
    c.reason = "the solution has no disk frames for this robot";
    return c;
  }
  if (sol.backbone.empty() || sol.backbone.front().s != 0.0) {
    c.reason = "the solution has no backbone sample at the base";
    return c;
  }
  const SceneEffects e = scene.active_effects();
  const cosserat::Section section = cosserat::Section::from(scene);
  const std::vector<double>& T = scene.actuation.values;
  Vec3 F = Vec3::Zero(), M = Vec3::Zero();
  double fs = 0.0, ms = 0.0;
  auto add = [&](const Vec3& f, const Vec3& at) {  // a force f applied at point `at`
    F += f;
    const Vec3 m = at.cross(f);
    M += m;
    fs += f.norm();
    ms += m.norm();
  };

  // The rod's internal wrench at the base cut acts as -n(0), -m(0) on the free body.
  const BackboneSample& b0 = sol.backbone.front();
  add(-b0.n, Vec3::Zero());
  M -= b0.m;
  ms += b0.m.norm();

  // Tendons' pull at the base cut: -T d_k at the base hole r_k.
  const Vec3 u0 = section.curvature(Mat3::Identity(), b0.m);
  const Vec3 v0 = section.strain(Mat3::Identity(), b0.n);
  for (const RoutedTendon& t : rt.tendons) {
    const double Tk = T[t.index];
    if (Tk == 0.0) continue;
    Vec3 d;
    if (vc) {
      d = (v0 + u0.cross(t.r)).normalized();
    } else {
      d = (tendon::hole_position(sol.disk_frames[1], t) - t.r).normalized();
      if (e.disk_normal_force_removed) {
        // Forces Eq. 58 drops at every disk the tendon passes through (not at its end disk).
        for (int j = 1; j < t.end_disk; ++j) {
          const Frame& fj = sol.disk_frames[j];
          const Vec3 P = tendon::hole_position(fj, t);
          const Vec3 Fp = Tk * ((tendon::hole_position(sol.disk_frames[j - 1], t) - P).normalized() +
                                (tendon::hole_position(sol.disk_frames[j + 1], t) - P).normalized());
          const Vec3 z = fj.R.col(2);
          const Vec3 dropped = Fp.dot(z) * z;  // acts on the tendon-disk system, not on the disk
          c.eq58_force -= dropped;
          c.eq58_moment -= P.cross(dropped);
          add(-dropped, P);
        }
      }
    }
    add(-Tk * d, t.r);
  }

  // Tip wrench at the tip point.
  if (e.tip_wrench) {
    add(scene.loads.tip_force, sol.disk_frames[N].p);
    M += scene.loads.tip_moment;
    ms += scene.loads.tip_moment.norm();
  }
  // Disk weights.
  if (e.disk_weight)
    for (int j = 1; j <= N; ++j)
      add(scene.robot.segments[rt.disk_segment[j]].disk_mass * scene.loads.gravity, sol.disk_frames[j].p);
  // Backbone weight: w per unit reference length, its moment int p ds x w (Hermite rule).
  if (e.backbone_weight) {
    const Vec3 w = section.weight;
    Vec3 P = Vec3::Zero();  // int p ds
    double len = 0.0;
    for (std::size_t i = 1; i < sol.backbone.size(); ++i) {
      const BackboneSample& a = sol.backbone[i - 1];
      const BackboneSample& b = sol.backbone[i];
      const double h = b.s - a.s;
      const Vec3 ta = a.frame.R * section.strain(a.frame.R, a.n);
      const Vec3 tb = b.frame.R * section.strain(b.frame.R, b.n);
      P += 0.5 * h * (a.frame.p + b.frame.p) + h * h / 12.0 * (ta - tb);
      len += h;
    }
    const Vec3 W = len * w;
    F += W;
    fs += W.norm();
    const Vec3 m = P.cross(w);
    M += m;
    ms += m.norm();
  }
  c.force = F;
  c.moment = M;
  // Forces and moments are judged together: a load case of pure moments (fs ~ 0) is judged on
  // ms / L, and one of forces through the base (ms ~ 0) on fs L.
  const double L = scene.robot.total_length();
  c.force_scale = std::max(fs, ms / L);
  c.moment_scale = std::max(ms, fs * L);
  if (!(F.allFinite() && M.allFinite())) {
    c.reason = "non-finite values in the solution";
    return c;
  }
  c.evaluated = true;
  return c;
}

}  // namespace tdcr
