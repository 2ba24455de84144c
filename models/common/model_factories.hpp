// Private to models/: the factory of each model (the registry's `make` column), defined in that
// model's folder.
#pragma once

#include <memory>

#include "tdcr/models/static_model.hpp"

namespace tdcr::detail {
std::unique_ptr<StaticModel> make_cc_model(const Robot& robot, const Effects& effects);
std::unique_ptr<StaticModel> make_ccsub_model(const Robot& robot, const Effects& effects);
std::unique_ptr<StaticModel> make_prb_model(const Robot& robot, const Effects& effects);
std::unique_ptr<StaticModel> make_vc_model(const Robot& robot, const Effects& effects);
std::unique_ptr<StaticModel> make_vcref_model(const Robot& robot, const Effects& effects);
}  // namespace tdcr::detail
