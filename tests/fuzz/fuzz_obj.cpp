// libFuzzer target: the OBJ reader (io/obj_reader), then the half-edge mesh built from what it returns.
// A reader may only reject with a topotrack::Error; any other exception, a sanitizer report or a result that
// breaks the reader's guarantees (fuzz_check.hpp) is a finding.
#include <cstdint>
#include <string_view>

#include "io/error.hpp"
#include "io/obj_reader.hpp"
#include "tests/fuzz/fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace topotrack;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  MeshData d;
  try {
    d = parse_obj(text, "fuzz.obj");
  } catch (const Error&) {
    return 0;
  }
  fuzz::check_mesh_data(d);
  fuzz::build_mesh(d);
  return 0;
}
