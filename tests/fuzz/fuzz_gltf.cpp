// libFuzzer harness: the glTF loader (load_gltf: JSON types, byte ranges, the conversion) on
// arbitrary .gltf text or .glb bytes, through a file as a user's scene goes. Bad input must end
// in an InputError.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "kernel/errors.hpp"
#include "scene/gltf_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = tbdr::fuzz::write_input("fuzz.gltf", data, size);
  try {
    (void)tbdr::load_gltf(path);
  } catch (const tbdr::InputError&) {
  }
  return 0;
}
