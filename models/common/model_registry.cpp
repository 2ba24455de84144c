#include <algorithm>
#include <cctype>

#include "common/model_factories.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/model_selection.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr {

ModelKind parse_model_kind(const std::string& name) {
  std::string n = name;
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return std::tolower(c); });
  if (n == "cc") return ModelKind::CC;
  if (n == "ccsub") return ModelKind::CCsub;
  if (n == "prb") return ModelKind::PRB;
  if (n == "vc") return ModelKind::VC;
  if (n == "vcref") return ModelKind::VCref;
  throw InputError("model", name, "unknown model (expected cc, ccsub, prb, vc or vcref)");
}

std::string to_string(ModelKind kind) {
  switch (kind) {
    case ModelKind::CC: return "cc";
    case ModelKind::CCsub: return "ccsub";
    case ModelKind::PRB: return "prb";
    case ModelKind::VC: return "vc";
    case ModelKind::VCref: return "vcref";
  }
  return "unknown";
}

std::unique_ptr<StaticModel> make_model(ModelKind kind, const Scene& scene) {
  scene.validate();
  switch (kind) {
    case ModelKind::CC: return detail::make_cc_model(scene);
    case ModelKind::CCsub: return detail::make_ccsub_model(scene);
    case ModelKind::PRB: return detail::make_prb_model(scene);
    case ModelKind::VC: return detail::make_vc_model(scene);
    case ModelKind::VCref: return detail::make_vcref_model(scene);
  }
  throw InputError("model", to_string(kind), "unknown model");
}

Solution solve(const Scene& scene, const Solution* warm_start) {
  if (scene.model == "auto") return solve_auto(scene, 0.01, warm_start);  // default accuracy: 1 %
  auto model = make_model(parse_model_kind(scene.model), scene);
  auto ws = model->make_workspace();
  return model->solve(*ws, warm_start);
}

}  // namespace tdcr
