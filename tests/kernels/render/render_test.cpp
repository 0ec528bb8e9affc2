// Tests of the ray tracer, camera, PNG and image helpers (kernels/render).
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "io/error.hpp"
#include "kernels/render/camera.hpp"
#include "kernels/render/png.hpp"
#include "kernels/render/raytracer.hpp"
#include "kernels/render/render_mesh.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

RenderMesh from_soup(const test::Soup& s) {
  RenderMesh m;
  m.positions = s.positions;
  m.triangles = s.triangles;
  return m;
}

TEST(Png, RoundTripAndErrors) {
  Image im(37, 21);
  for (std::size_t i = 0; i < im.rgb.size(); ++i) im.rgb[i] = std::uint8_t((i * 7919) % 251);
  const std::string bytes = encode_png(im);
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
  const Image back = decode_png(bytes, "mem");
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 21);
  EXPECT_EQ(back.rgb, im.rgb);
  EXPECT_THROW(decode_png("not a png at all", "junk"), InvalidInput);
  EXPECT_THROW(decode_png(bytes.substr(0, bytes.size() / 2), "half"), InvalidInput);
  EXPECT_THROW(encode_png(Image()), InvalidInput);
  EXPECT_THROW(read_png("/nonexistent/dir/x.png"), IoError);

  const auto dir = std::filesystem::temp_directory_path() / "topotrack_render_test";
  std::filesystem::create_directories(dir);
  write_png(dir / "a.png", im);
  EXPECT_EQ(read_png(dir / "a.png").rgb, im.rgb);
  EXPECT_THROW(write_png(dir / "missing_sub" / "a.png", im), IoError);
  std::filesystem::remove_all(dir);
}

TEST(Render, SphereSilhouetteMatchesProjectedDisk) {
  // A sphere of radius r seen from distance d subtends a cone of half-angle asin(r/d); its image is a disk
  // of radius tan(asin(r/d)) / tan(fov/2) * H/2 pixels.
  const RenderScene scene(from_soup(test::icosphere(5)));
  Camera cam;
  cam.eye = Vec3(0, 0, 4);
  cam.target = Vec3::Zero();
  cam.fov_y_deg = 30;
  RenderParams p;
  p.width = p.height = 300;
  p.samples_per_axis = 1;
  RenderReport rep;
  const Image im = render(scene, cam, p, &rep);
  const double half = 15 * std::numbers::pi / 180;
  const double radius_px = std::tan(std::asin(1.0 / 4.0)) / std::tan(half) * 150;
  const double expected = std::numbers::pi * radius_px * radius_px;
  EXPECT_NEAR(rep.covered_pixels / expected, 1.0, 0.02) << rep.covered_pixels << " vs " << expected;
  EXPECT_EQ(rep.rays, 300u * 300u);
  // Corners are background, the centre is lit surface.
  EXPECT_EQ(im.pixel(0, 0)[0], 255);
  EXPECT_LT(im.pixel(150, 150)[0], 255);
  EXPECT_GT(im.pixel(150, 150)[0], 40);
}

TEST(Render, DeterministicAcrossThreadCounts) {
  test::Soup s = test::merge(test::icosphere(4), test::torus(64, 32, 1.2, 0.3));
  test::jitter(s, 0.01, 7);
  RenderMesh m = from_soup(s);
  for (std::size_t i = 0; i < m.positions.size(); ++i)
    for (int c = 0; c < 3; ++c) m.colors.push_back(float(0.5 + 0.5 * std::sin(3 * m.positions[i][c] + c)));
  BoundingBox box;
  for (const Vec3& q : m.positions) box.extend(q);
  const Camera cam = fit_camera(box, {.azimuth_deg = 40, .elevation_deg = 25});
  RenderParams p;
  p.width = 160;
  p.height = 120;
  p.wireframe = true;
  auto run = [&](int threads) {
    tbb::task_arena arena(threads);
    Image out;
    arena.execute([&] { out = render(m, cam, p); });
    return out;
  };
  const Image a = run(1), b = run(2);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(compare_images(a, b).max_abs, 0);
}

TEST(Render, ColoursAndWireframeShow) {
  RenderMesh m = from_soup(test::icosphere(3));
  m.colors.assign(3 * m.positions.size(), 0.0f);
  for (std::size_t i = 0; i < m.positions.size(); ++i) m.colors[3 * i] = 1.0f;  // red
  Camera cam;
  cam.eye = Vec3(0, 0, 4);
  RenderParams p;
  p.width = p.height = 128;
  const Image red = render(m, cam, p);
  const std::uint8_t* c = red.pixel(64, 64);
  EXPECT_GT(c[0], 100);
  EXPECT_LT(c[1], 60);
  EXPECT_LT(c[2], 60);
  p.wireframe = true;
  p.wire_width_px = 2;
  const Image wire = render(m, cam, p);
  const ImageDifference d = compare_images(red, wire);
  EXPECT_GT(d.share_differing, 0.05);
  EXPECT_LT(d.share_differing, 0.6);
}

TEST(Render, FittedCameraSeesTheWholeBox) {
  BoundingBox box;
  box.extend(Vec3(-1, -2, -0.5));
  box.extend(Vec3(3, 1, 0.5));
  for (double az : {0.0, 90.0, 200.0}) {
    const Camera cam = fit_camera(box, {.azimuth_deg = az, .elevation_deg = 30, .aspect = 1.5});
    const double t = std::tan(0.5 * cam.fov_y_deg * std::numbers::pi / 180);
    for (int k = 0; k < 8; ++k) {
      const Vec3 q((k & 1) ? box.max.x() : box.min.x(), (k & 2) ? box.max.y() : box.min.y(),
                   (k & 4) ? box.max.z() : box.min.z());
      const Vec3 d = q - cam.eye;
      const double z = d.dot(cam.forward());
      ASSERT_GT(z, 0);
      EXPECT_LE(std::abs(d.dot(cam.right()) / z), 1.5 * t);
      EXPECT_LE(std::abs(d.dot(cam.true_up()) / z), t);
    }
  }
  // A turntable step about the up axis keeps the distance to the target.
  const Camera cam = fit_camera(box);
  const Camera turned = orbit(cam, cam.up, 90);
  EXPECT_NEAR((turned.eye - turned.target).norm(), (cam.eye - cam.target).norm(), 1e-9);
  EXPECT_NEAR((turned.eye - cam.eye).norm(), std::sqrt(2.0) * (cam.eye - cam.target).cross(cam.up).norm(), 1e-9);
  EXPECT_THROW(fit_camera(BoundingBox()), InvalidInput);
  EXPECT_THROW(fit_camera(box, {.fov_y_deg = 190}), InvalidInput);
}

TEST(Render, RejectsBadInput) {
  RenderMesh m = from_soup(test::tetrahedron());
  RenderMesh bad = m;
  bad.triangles[0][1] = 99;
  EXPECT_THROW(RenderScene{std::move(bad)}, InvalidInput);
  RenderMesh bad_colors = m;
  bad_colors.colors = {1, 0};
  EXPECT_THROW(RenderScene{std::move(bad_colors)}, InvalidInput);
  RenderMesh nan = m;
  nan.positions[0].x() = std::nan("");
  EXPECT_THROW(RenderScene{std::move(nan)}, InvalidInput);
  const RenderScene scene(std::move(m));
  Camera cam;
  RenderParams p;
  p.width = 0;
  EXPECT_THROW(render(scene, cam, p), InvalidInput);
  p.width = 10;
  p.samples_per_axis = 9;
  EXPECT_THROW(render(scene, cam, p), InvalidInput);
  cam.target = cam.eye;
  p.samples_per_axis = 1;
  EXPECT_THROW(render(scene, cam, p), InvalidInput);
}

TEST(Render, EmptySceneIsBackground) {
  const RenderScene scene(RenderMesh{});
  RenderParams p;
  p.width = p.height = 8;
  RenderReport rep;
  const Image im = render(scene, Camera{}, p, &rep);
  EXPECT_EQ(rep.covered_pixels, 0);
  for (std::uint8_t b : im.rgb) EXPECT_EQ(b, 255);
}

TEST(Image, ContactSheetAndCompare) {
  std::vector<Image> tiles;
  for (int k = 0; k < 5; ++k) tiles.emplace_back(10 + k, 8, std::uint8_t(10 * k));
  const Image sheet = contact_sheet(tiles, {.columns = 3, .gap = 2});
  EXPECT_EQ(sheet.width, 3 * 14 + 4 * 2);
  EXPECT_EQ(sheet.height, 2 * 8 + 3 * 2);
  EXPECT_EQ(sheet.pixel(0, 0)[0], 255);
  EXPECT_EQ(sheet.pixel(2 + 2, 2)[0], 0);                // first tile (10 wide, centred in 14)
  EXPECT_EQ(sheet.pixel(2 + 14 + 2 + 7, 2 + 8 + 2 + 3)[0], 40);  // tile 4 (14 wide): second row, second column
  EXPECT_THROW(contact_sheet(std::span<const Image>()), InvalidInput);
  const ImageDifference d = compare_images(tiles[1], Image(11, 8, 13));
  EXPECT_EQ(d.max_abs, 3);
  EXPECT_DOUBLE_EQ(d.mean_abs, 3);
  EXPECT_DOUBLE_EQ(d.share_differing, 1);
  EXPECT_DOUBLE_EQ(compare_images(tiles[1], Image(11, 8, 13), {.tolerance = 3, .ignore = std::nullopt}).share_differing, 0);
  EXPECT_THROW(compare_images(tiles[0], tiles[1]), InvalidInput);
}

TEST(Image, ComparePercentileAndIgnoredBackground) {
  // 100 pixels: 40 white in both (background), 50 equal grey, 9 differing by 20 in one channel, 1 by 200.
  Image a(10, 10, 255), b(10, 10, 255);
  for (int p = 40; p < 100; ++p) {
    a.rgb[3 * p] = a.rgb[3 * p + 1] = a.rgb[3 * p + 2] = 100;
    b.rgb[3 * p] = b.rgb[3 * p + 1] = b.rgb[3 * p + 2] = 100;
  }
  for (int p = 90; p < 99; ++p) b.rgb[3 * p + 1] = 120;
  b.rgb[3 * 99] = 255;
  b.rgb[3 * 99 + 1] = 255;  // white in one image only: compared
  b.rgb[3 * 99 + 2] = 255;
  const ImageDifference all = compare_images(a, b, {.tolerance = 5, .ignore = std::nullopt});
  EXPECT_EQ(all.pixels_compared, 100u);
  EXPECT_EQ(all.pixel_p95, 20);
  EXPECT_EQ(all.max_abs, 155);
  EXPECT_DOUBLE_EQ(all.share_differing, 0.10);
  EXPECT_DOUBLE_EQ(all.pixel_mean, (9 * 20 + 155) / 100.0);
  const ImageDifference fg = compare_images(a, b, {.tolerance = 5, .ignore = std::array<std::uint8_t, 3>{255, 255, 255}});
  EXPECT_EQ(fg.pixels_compared, 60u);
  EXPECT_DOUBLE_EQ(fg.share_differing, 10 / 60.0);
  EXPECT_EQ(fg.pixel_p95, 20);   // the 57th of 60 sorted differences
  EXPECT_DOUBLE_EQ(fg.mean_abs, (9 * 20 + 3 * 155) / (3 * 60.0));
  const ImageDifference none = compare_images(Image(4, 4, 255), Image(4, 4, 255), {.ignore = std::array<std::uint8_t, 3>{255, 255, 255}});
  EXPECT_EQ(none.pixels_compared, 0u);
  EXPECT_EQ(none.share_differing, 0);
}

TEST(RenderMesh, FromMeshData) {
  MeshData d;
  d.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  d.triangles = {{0, 1, 2}};
  d.attributes.push_back({"color", 4, {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1}});
  const RenderMesh r = to_render_mesh(d);
  EXPECT_EQ(r.colors, (std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_EQ(r.triangles[0][2], 2u);
  EXPECT_TRUE(to_render_mesh(d, "missing").colors.empty());
  MeshData bad = d;
  bad.attributes[0].width = 2;
  bad.attributes[0].values.resize(6);
  EXPECT_THROW(to_render_mesh(bad), InvalidInput);
  bad = d;
  bad.triangles[0][1] = -1;
  EXPECT_THROW(to_render_mesh(bad), InvalidInput);
  bad = d;
  bad.triangles[0][1] = 3;
  EXPECT_THROW(to_render_mesh(bad), InvalidInput);
}

}  // namespace
}  // namespace topotrack
