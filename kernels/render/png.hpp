#pragma once
//! PNG encoding and decoding of RGB images through libpng's simplified API; files are written atomically.
#include <filesystem>
#include <string>
#include <string_view>

#include "kernels/render/image.hpp"

namespace topotrack {

//! The PNG bytes of `image` (8-bit RGB). \throw InvalidInput for an empty or inconsistent image.
std::string encode_png(const Image& image);
//! Decode PNG bytes of any colour type to 8-bit RGB (alpha composited on black by libpng, grey expanded).
//! \throw InvalidInput "<name>: <libpng message>" for bytes that are not a valid PNG.
Image decode_png(std::string_view bytes, const std::string& name);

//! Write atomically (io/atomic_file.hpp). \throw IoError naming the path; InvalidInput as encode_png.
void write_png(const std::filesystem::path& path, const Image& image);
//! \throw IoError when unreadable, InvalidInput when not a PNG, naming the path.
Image read_png(const std::filesystem::path& path);

}  // namespace topotrack
