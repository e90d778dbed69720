// The frame's images (`tbdrsim run --images`): a G-buffer attachment's image shows what it stands
// for, from the surfaces the frame stored (base colour in sRGB, normals as n/2 + 1/2 unorm), and
// a visibility attachment's its triangle ids; G-buffer and visibility attachments carry no colour
// array of their own (nothing writes one).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "app/image_output.hpp"
#include "app/run_driver.hpp"
#include "models/command_processor.hpp"
#include "models/hw_config.hpp"
#include "atrium_trace_setup.hpp"

namespace tbdr {
namespace {

class FrameImages : public testing_support::AtriumTechniqueSuite {
 protected:
  /// `technique`'s small frame with colours, its images written into a fresh folder.
  std::filesystem::path write(const std::string& technique, FrameResult& frame) {
    frame = simulate_frame(small_trace(technique), "t.trace", *scene_, resolve_config({}, {}).hw, FrameOptions{.colour = true});
    const auto dir = std::filesystem::temp_directory_path() / ("tbdrsim_test_frame_images_" + technique);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    write_frame_images(frame, dir.string());
    return dir;
  }
  /// The attachment holding the stored surfaces of `usage`.
  static const AttachmentImage& store_of(const FrameResult& f, AttachmentUsage usage) {
    for (const auto& [name, img] : f.images.attachments) {
      if (img.usage == usage && !img.surface.empty()) return img;
    }
    throw std::logic_error("no stored surfaces");
  }
};

TEST_F(FrameImages, GbufferImagesShowTheStoredAlbedoAndNormals) {
  FrameResult f;
  const auto dir = write("deferred", f);
  for (const auto& [name, img] : f.images.attachments) {
    if (img.usage == AttachmentUsage::Gbuffer) {
      EXPECT_TRUE(img.color.empty()) << name << ": a G-buffer target with a colour array";
    }
  }
  const AttachmentImage& g = store_of(f, AttachmentUsage::Gbuffer);
  const ImageRGB8 albedo = read_png((dir / "attachment_albedo.png").string());
  const ImageRGB8 normal = read_png((dir / "attachment_normal.png").string());
  const int w = f.images.width, h = f.images.height;
  ASSERT_EQ(albedo.width, w);
  ASSERT_EQ(normal.height, h);
  // Pixel for pixel: written surfaces show their albedo (sRGB) and normal (n/2 + 1/2 on 0..255),
  // the others black; the frame has both, and its normals are not all alike.
  std::size_t written = 0, unwritten = 0, distinct_normals = 0;
  Rgb8 first_normal{};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      if (!g.surface_valid[p]) {
        ++unwritten;
        EXPECT_EQ(albedo.at(x, y), (Rgb8{0, 0, 0}));
        EXPECT_EQ(normal.at(x, y), (Rgb8{0, 0, 0}));
        continue;
      }
      const SurfacePoint s = g.surface[p];
      const Rgb8 a = albedo.at(x, y), n = normal.at(x, y);
      EXPECT_EQ(a.r, linear_to_srgb8(s.albedo.x));
      EXPECT_EQ(a.b, linear_to_srgb8(s.albedo.z));
      EXPECT_EQ(n.g, static_cast<int>(std::lround(std::clamp(s.normal.y * 0.5f + 0.5f, 0.0f, 1.0f) * 255.0f)));
      if (written++ == 0) first_normal = n;
      if (!(n == first_normal)) ++distinct_normals;
    }
  }
  EXPECT_GT(written, static_cast<std::size_t>(w * h) / 2);  // the atrium fills most of the frame
  EXPECT_GT(unwritten, 0u);                                  // and the sky stays unwritten
  EXPECT_GT(distinct_normals, written / 4);
}

TEST_F(FrameImages, VisibilityAttachmentShowsItsTriangleIds) {
  FrameResult f;
  const auto dir = write("visibility_buffer", f);
  const AttachmentImage& v = store_of(f, AttachmentUsage::Visibility);
  std::string name;
  for (const auto& [n, img] : f.images.attachments) {
    if (&img == &v) name = n;
  }
  const ImageRGB8 ids = read_png((dir / ("attachment_" + name + ".png")).string());
  const int w = f.images.width;
  for (int y = 0; y < ids.height; y += 7) {
    for (int x = 0; x < ids.width; x += 5) {
      const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      const Rgb8 expected = v.surface_valid[p] ? id_color(v.surface.site(p).triangle + 1) : Rgb8{0, 0, 0};
      EXPECT_EQ(ids.at(x, y), expected) << x << "," << y;
    }
  }
}

// The images are encoded as independent jobs on the run's threads: at 1 and 3 threads the same
// files, byte for byte, listed in the same order (the attachments, color.png, the ids and the
// heat maps), and the encoding's CPU seconds reported.
TEST_F(FrameImages, SameFilesAndListAtAnyThreadCount) {
  FrameResult f;
  const auto one = write("deferred", f);
  const auto three = std::filesystem::temp_directory_path() / "tbdrsim_test_frame_images_deferred_3";
  std::filesystem::remove_all(three);
  std::filesystem::create_directories(three);
  double cpu1 = -1, cpu3 = -1;
  const std::vector<std::string> list1 = write_frame_images(f, one.string(), 1, &cpu1);
  const std::vector<std::string> list3 = write_frame_images(f, three.string(), 3, &cpu3);
  ASSERT_EQ(list1.size(), list3.size());
  ASSERT_GE(list1.size(), 8u);  // albedo, color, normal attachments, color.png, depth, ids, 3 heat maps
  auto read = [](const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  for (std::size_t i = 0; i < list1.size(); ++i) {
    const auto name = std::filesystem::path(list1[i]).filename();
    EXPECT_EQ(name, std::filesystem::path(list3[i]).filename()) << i;
    const std::string a = read(list1[i]), b = read(list3[i]);
    EXPECT_FALSE(a.empty()) << name;
    EXPECT_EQ(a, b) << name;
  }
  const auto color = std::find_if(list1.begin(), list1.end(), [](const std::string& p) { return p.ends_with("/color.png"); });
  ASSERT_NE(color, list1.end());
  EXPECT_TRUE(std::filesystem::path(*(color - 1)).filename().string().starts_with("attachment_") ||
              std::filesystem::path(*(color - 1)).filename().string().starts_with("depth_"));
  EXPECT_EQ(std::filesystem::path(*(color + 1)).filename(), "triangle_id.png");
  EXPECT_GT(cpu1, 0.0);
  EXPECT_GT(cpu3, 0.0);
  std::filesystem::remove_all(three);
}

}  // namespace
}  // namespace tbdr
