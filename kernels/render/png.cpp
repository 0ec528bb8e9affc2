#include "kernels/render/png.hpp"

#include <png.h>

#include <cstring>

#include "io/atomic_file.hpp"
#include "io/error.hpp"
#include "io/mapped_file.hpp"

namespace topotrack {

std::string encode_png(const Image& image) {
  if (image.width <= 0 || image.height <= 0 || image.rgb.size() != std::size_t(3) * image.width * image.height)
    TT_THROW(InvalidInput, "encode_png: bad image " << image.width << "x" << image.height << " with "
                                                    << image.rgb.size() << " bytes");
  png_image img;
  std::memset(&img, 0, sizeof img);
  img.version = PNG_IMAGE_VERSION;
  img.width = png_uint_32(image.width);
  img.height = png_uint_32(image.height);
  img.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  const png_int_32 stride = png_int_32(3 * image.width);
  if (!png_image_write_to_memory(&img, nullptr, &size, 0, image.rgb.data(), stride, nullptr))
    TT_THROW(InvalidInput, "encode_png: " << img.message);
  std::string out(size, '\0');
  if (!png_image_write_to_memory(&img, out.data(), &size, 0, image.rgb.data(), stride, nullptr))
    TT_THROW(InvalidInput, "encode_png: " << img.message);
  out.resize(size);
  return out;
}

Image decode_png(std::string_view bytes, const std::string& name) {
  png_image img;
  std::memset(&img, 0, sizeof img);
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&img, bytes.data(), bytes.size()))
    TT_THROW(InvalidInput, name << ": not a PNG: " << img.message);
  img.format = PNG_FORMAT_RGB;
  if (img.width == 0 || img.height == 0 || img.width > (1u << 15) || img.height > (1u << 15)) {
    png_image_free(&img);
    TT_THROW(InvalidInput, name << ": unsupported PNG size " << img.width << "x" << img.height);
  }
  Image out(int(img.width), int(img.height));
  if (!png_image_finish_read(&img, nullptr, out.rgb.data(), png_int_32(3 * img.width), nullptr))
    TT_THROW(InvalidInput, name << ": corrupt PNG: " << img.message);
  return out;
}

void write_png(const std::filesystem::path& path, const Image& image) {
  write_file_atomic(path, encode_png(image));
}

Image read_png(const std::filesystem::path& path) {
  const MappedFile file(path);
  return decode_png(file.text(), path.string());
}

}  // namespace topotrack
