// libFuzzer target: the PLY reader (io/ply_reader; ascii, binary little and big endian), then the half-edge
// mesh built from what it returns. A reader may only reject with a topotrack::Error; any other exception
// (bad_alloc from a lying count included), a sanitizer report or a result that breaks the reader's
// guarantees (fuzz_check.hpp) is a finding.
#include <cstdint>
#include <string_view>

#include "io/error.hpp"
#include "io/ply_reader.hpp"
#include "tests/fuzz/fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace topotrack;
  MeshData d;
  try {
    d = parse_ply(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.ply");
  } catch (const Error&) {
    return 0;
  }
  fuzz::check_mesh_data(d);
  fuzz::build_mesh(d);
  return 0;
}
