// Private to models/: the factory of each model, defined in that model's folder. A model that
// is not built yet defines its factory to throw InputError naming the model.
#pragma once

#include <memory>

#include "tdcr/models/static_model.hpp"

namespace tdcr::detail {
std::unique_ptr<StaticModel> make_cc_model(const Scene& scene);
std::unique_ptr<StaticModel> make_ccsub_model(const Scene& scene);
std::unique_ptr<StaticModel> make_prb_model(const Scene& scene);
std::unique_ptr<StaticModel> make_vc_model(const Scene& scene);
std::unique_ptr<StaticModel> make_vcref_model(const Scene& scene);
}  // namespace tdcr::detail
