// Placeholder until the ccsub model lands: a clear error instead of a missing symbol.
#include "common/model_factories.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr::detail {
std::unique_ptr<StaticModel> make_ccsub_model(const Scene&) {
  throw InputError("model", "ccsub", "this model is not available in this build yet");
}
}  // namespace tdcr::detail
