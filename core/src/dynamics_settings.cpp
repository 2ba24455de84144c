// The checks and the interpolation of the scene's dynamics keys (DynamicsSettings, Timeline in
// tdcr/core/scene.hpp): plain data, so that the scene file can be read and checked in core.
#include <cmath>
#include <string>

#include "tdcr/core/error.hpp"
#include "tdcr/core/scene.hpp"

namespace tdcr {

namespace {

std::string text(double v) { return format_value(v); }

// The reason of an InputError (its message without the field and the value).
std::string reason_of(const InputError& e) {
  std::string r = std::string(e.what()).substr(e.field().size() + 2);
  const std::string got = " (got " + e.value() + ")";
  if (!e.value().empty() && r.size() >= got.size() && r.compare(r.size() - got.size(), got.size(), got) == 0)
    r.resize(r.size() - got.size());
  return r;
}

void require_time(const std::string& field, double v) {
  if (!std::isfinite(v) || v < 0.0) throw InputError(field, text(v), "must be a finite time (s) >= 0");
}

}  // namespace

void DynamicsSettings::validate() const {
  require_time("dynamics.bending_damping_time", bending_damping_time);
  require_time("dynamics.shear_damping_time", shear_damping_time);
  if (!std::isfinite(air_drag) || air_drag < 0.0)
    throw InputError("dynamics.air_drag", text(air_drag), "must be finite and >= 0 (N s^2/m^3)");
  if (!std::isfinite(alpha) || alpha < -0.5 || alpha > 0.0)
    throw InputError("dynamics.alpha", text(alpha), "must be in [-0.5, 0] (BDF-alpha; 0 is BDF2)");
}

void Timeline::at(double t, ModelInput& out) const {
  if (entries.empty()) throw InputError("timeline", "[]", "has no entry: there is no input to simulate");
  // The entry whose interval holds t (linear search: timelines are short).
  std::size_t k = 0;
  while (k + 1 < entries.size() && entries[k + 1].t <= t) ++k;
  const ModelInput& a = entries[k].input;
  // Copy-assignment reuses out's storage where the sizes agree.
  out.actuation.kind = a.actuation.kind;
  out.actuation.convention = a.actuation.convention;
  out.actuation.values.assign(a.actuation.values.begin(), a.actuation.values.end());
  out.actuation.kinds.assign(a.actuation.kinds.begin(), a.actuation.kinds.end());
  out.loads = a.loads;
  if (k + 1 >= entries.size() || t <= entries[k].t) return;
  const ModelInput& b = entries[k + 1].input;
  const double s = (t - entries[k].t) / (entries[k + 1].t - entries[k].t);
  for (std::size_t i = 0; i < out.actuation.values.size() && i < b.actuation.values.size(); ++i)
    out.actuation.values[i] += s * (b.actuation.values[i] - a.actuation.values[i]);
  out.loads.tip_force += s * (b.loads.tip_force - a.loads.tip_force);
  out.loads.tip_moment += s * (b.loads.tip_moment - a.loads.tip_moment);
  out.loads.gravity += s * (b.loads.gravity - a.loads.gravity);
}

ModelInput Timeline::at(double t) const {
  ModelInput in;
  at(t, in);
  return in;
}

void Timeline::validate(const Robot& robot) const {
  if (entries.empty()) throw InputError("timeline", "[]", "must list at least one entry {\"t\": ..., \"actuation\": ...}");
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const std::string p = "timeline[" + std::to_string(i) + "]";
    const double t = entries[i].t;
    if (!std::isfinite(t)) throw InputError(p + ".t", text(t), "must be a finite time (s)");
    if (i > 0 && !(t > entries[i - 1].t))
      throw InputError(p + ".t", text(t),
                       "must be greater than the previous entry's t (" + text(entries[i - 1].t) + ")");
    try {
      entries[i].input.validate(robot);
    } catch (const InputError& e) {
      // ModelInput names `actuation...` / `loads...`: say which entry.
      throw InputError(p + "." + e.field(), e.value(), reason_of(e));
    }
    if (i > 0) {
      const Actuation& a = entries[i - 1].input.actuation;
      const Actuation& b = entries[i].input.actuation;
      if (a.kind != b.kind || a.kinds != b.kinds || a.convention != b.convention)
        throw InputError(p + ".actuation", b.kind == Actuation::Kind::Tensions ? "tensions" : "displacements",
                         "gives its tendons another way than the previous entry (tensions and displacements "
                         "cannot be interpolated into each other)");
    }
  }
}

}  // namespace tdcr
