// Placeholder until the vcref model lands: a clear error instead of a missing symbol.
#include "common/model_factories.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr::detail {
std::unique_ptr<StaticModel> make_vcref_model(const Scene&) {
  throw InputError("model", "vcref", "this model is not available in this build yet");
}
}  // namespace tdcr::detail
