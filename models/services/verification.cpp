#include "tdcr/models/verification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "physics/load_case.hpp"
#include "physics/tendon_path.hpp"
#include "tdcr/core/robot.hpp"
#include "tdcr/models/cosserat_rod.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

double EquilibriumCheck::relative_error() const {
  if (!evaluated) return std::numeric_limits<double>::infinity();
  const double f = force_scale > 0.0 ? force.norm() / force_scale : force.norm();
  const double m = moment_scale > 0.0 ? moment.norm() / moment_scale : moment.norm();
  return std::max(f, m);
}

namespace {

// The check for a model row of the registry, its robot and effects, one input and a Solution.
EquilibriumCheck verify(const ModelInfo& info, const Robot& robot, const Effects& effects, const ModelInput& input,
                        const Solution& sol) {
  EquilibriumCheck c;
  if (!info.capabilities.backbone_wrench) {
    c.reason = "model '" + std::string(info.name) +
               "' reports no internal wrench at the base; check its own residual (summary) instead";
    return c;
  }
  const TendonRouting rt = TendonRouting::from(robot);
  const int N = rt.disk_count() - 1;
  if (static_cast<int>(sol.disk_frames.size()) != N + 1) {
    c.reason = "the solution has no disk frames for this robot";
    return c;
  }
  if (sol.backbone.empty() || sol.backbone.front().s != 0.0) {
    c.reason = "the solution has no backbone sample at the base";
    return c;
  }
  physics::LoadCase loads;
  loads.bind(robot, rt, input);
  const cosserat::Section section = cosserat::Section::from(robot, effects, loads.backbone_weight());
  Vec3 F = Vec3::Zero(), M = Vec3::Zero();
  double fs = 0.0, ms = 0.0;
  auto add = [&](const Vec3& f, const Vec3& at) {  // a force f applied at point `at`
    F += f;
    const Vec3 m = at.cross(f);
    M += m;
    fs += f.norm();
    ms += m.norm();
  };
  auto add_moment = [&](const Vec3& m) {
    M += m;
    ms += m.norm();
  };

  // The rod's internal wrench at the base cut acts as -n(0), -m(0) on the free body.
  const BackboneSample& b0 = sol.backbone.front();
  add(-b0.n, Vec3::Zero());
  add_moment(-b0.m);

  // Tendons' pull at the base cut: -T d_k at the base hole r_k, d_k along the tendon's path there.
  const bool at_disks = info.capabilities.tendon_forces_at_disks;
  const Vec3 u0 = section.curvature(Mat3::Identity(), b0.m);
  const Vec3 v0 = section.strain(Mat3::Identity(), b0.n);
  for (const RoutedTendon& t : rt.tendons) {
    const double Tk = loads.tension(t.index);
    if (Tk == 0.0) continue;
    const Vec3 r = physics::tendon_offset(t, 0.0);
    const Vec3 d = (at_disks ? Vec3(physics::hole_position(sol.disk_frames[1], t, rt.disk_s[1]) - r)
                             : physics::tendon_tangent(v0, u0, r, physics::tendon_offset_rate(t, 0.0)))
                       .normalized();
    // Friction: the tension past the base hole, after the turn from the base axis into d.
    const double turn = std::atan2(d.cross(Vec3::UnitZ()).norm(), d.z());
    const TendonFriction& f = effects.tendon_friction;
    const double rate = f.on() ? f.sign() * f.of(t.index) : 0.0;
    add(-Tk * std::exp(rate * turn) * d, r);
  }
  // Forces Eq. 58 drops at the disks the tendons pass through: the disk wrench with the full
  // pass-through force minus the one the model applies. They act on the tendon-disk system.
  if (at_disks && effects.disk_normal_force == DiskNormalForce::Removed && loads.has_tension()) {
    const double* T = loads.full_tensions().data();
    for (int j = 1; j < N; ++j) {
      const tendon::DiskWrench full = tendon::disk_wrench(j, sol.disk_frames.data(), rt, T, false);
      const tendon::DiskWrench applied = tendon::disk_wrench(j, sol.disk_frames.data(), rt, T, true);
      const Vec3 dropped = full.force - applied.force;
      const Vec3 dropped_moment = sol.disk_frames[j].p.cross(dropped) + full.moment - applied.moment;
      c.eq58_force -= dropped;
      c.eq58_moment -= dropped_moment;
      F -= dropped;
      fs += dropped.norm();
      add_moment(-dropped_moment);
    }
  }

  // Tip wrench at the tip point.
  if (loads.has_tip_wrench()) {
    add(loads.tip_force(), sol.disk_frames[N].p);
    add_moment(loads.tip_moment());
  }
  // Disk weights.
  if (loads.has_disk_weight())
    for (int j = 1; j <= N; ++j) add(loads.disk_weight(j), sol.disk_frames[j].p);
  // Backbone weight: w per unit reference length, its moment int p ds x w (Hermite rule).
  if (loads.has_backbone_weight()) {
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
    add_moment(P.cross(w));
  }
  c.force = F;
  c.moment = M;
  // Forces and moments are judged together: a load case of pure moments (fs ~ 0) is judged on
  // ms / L, and one of forces through the base (ms ~ 0) on fs L.
  const double L = robot.total_length();
  c.force_scale = std::max(fs, ms / L);
  c.moment_scale = std::max(ms, fs * L);
  if (!(F.allFinite() && M.allFinite())) {
    c.reason = "non-finite values in the solution";
    return c;
  }
  c.evaluated = true;
  return c;
}

}  // namespace

EquilibriumCheck verify_equilibrium(const StaticModel& model, const ModelInput& input, const Solution& sol) {
  if (sol.model != model.name() || sol.model_fingerprint != model.fingerprint()) {
    EquilibriumCheck c;
    c.reason = "the solution is not of this model (model \"" + sol.model + "\", StaticModel::fingerprint)";
    return c;
  }
  return verify(model_info(model.kind()), model.robot(), model.effects(), input, sol);
}

EquilibriumCheck verify_equilibrium(const Scene& scene, const Solution& sol) {
  for (const ModelInfo& info : model_registry())
    if (sol.model == info.name) return verify(info, scene.robot, scene.effects, scene.input(), sol);
  EquilibriumCheck c;
  c.reason = "unknown model '" + sol.model + "'";
  return c;
}

}  // namespace tdcr
