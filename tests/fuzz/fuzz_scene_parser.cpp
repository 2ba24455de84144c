// libFuzzer target for the scene-file parser: any input must either parse into a valid scene
// (which then round-trips exactly through scene_to_json) or be rejected with tdcr::InputError.
// Any other exception, a crash, or a sanitizer report is a bug. The model name is the models
// layer's to check (tdcr::validate_scene), so any string parses here.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "tdcr/core/error.hpp"
#include "tdcr/core/scene_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  tdcr::Scene scene;
  try {
    scene = tdcr::parse_scene(text, "<fuzz>");
  } catch (const tdcr::InputError&) {
    return 0;  // rejected with a named field: the expected outcome for most inputs
  }
  // A scene that parsed must be valid and must round-trip.
  scene.validate();
  const std::string text_out = tdcr::scene_to_json(scene);
  const tdcr::Scene again = tdcr::parse_scene(text_out, "<round-trip>");
  if (tdcr::scene_to_json(again) != text_out) std::abort();
  return 0;
}
