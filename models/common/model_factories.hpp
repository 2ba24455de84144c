// Private to models/: the factory of each model (the registry's `make` column), defined in that
// model's folder, and, transitional, the scene-bound factories of models not yet moved to the
// StaticModel interface (wrapped by legacy_adapter.cpp).
#pragma once

#include <memory>

#include "tdcr/models/legacy_model.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::detail {
std::unique_ptr<StaticModel> make_cc_model(const Robot& robot, const Effects& effects);
std::unique_ptr<StaticModel> make_ccsub_model(const Robot& robot, const Effects& effects);
std::unique_ptr<StaticModel> make_prb_model(const Robot& robot, const Effects& effects);
std::unique_ptr<StaticModel> make_vc_model(const Robot& robot, const Effects& effects);
std::unique_ptr<StaticModel> make_vcref_model(const Robot& robot, const Effects& effects);

// Transitional: scene-bound models.
std::unique_ptr<LegacyStaticModel> make_legacy_cc_model(const Scene& scene);
std::unique_ptr<LegacyStaticModel> make_legacy_ccsub_model(const Scene& scene);
std::unique_ptr<LegacyStaticModel> make_legacy_prb_model(const Scene& scene);
std::unique_ptr<LegacyStaticModel> make_legacy_vc_model(const Scene& scene);
}  // namespace tdcr::detail
