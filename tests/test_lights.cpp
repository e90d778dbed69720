// Light sets: deterministic placement, finite attenuation, and the text file format.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "kernel/errors.hpp"
#include "kernel/random.hpp"
#include "scene/atrium.hpp"
#include "scene/lights.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;

const Scene& atrium1() {
  static const Scene s = make_atrium(1);
  return s;
}

std::string temp_path(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "tbdrsim_test_lights";
  fs::create_directories(dir);
  return (dir / name).string();
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool same_light(const Light& a, const Light& b) {
  return a.type == b.type && same_bits(a.position.x, b.position.x) && same_bits(a.position.y, b.position.y) &&
         same_bits(a.position.z, b.position.z) && same_bits(a.radius, b.radius) && same_bits(a.color.x, b.color.x) &&
         same_bits(a.color.y, b.color.y) && same_bits(a.color.z, b.color.z) && same_bits(a.intensity, b.intensity) &&
         (a.type == Light::Type::Point ||
          (same_bits(a.direction.x, b.direction.x) && same_bits(a.direction.y, b.direction.y) &&
           same_bits(a.direction.z, b.direction.z) && same_bits(a.cos_inner, b.cos_inner) &&
           same_bits(a.cos_outer, b.cos_outer)));
}

TEST(Lights, Pcg32IsTheReferenceGenerator) {
  // pcg32-demo (pcg-random.org, pcg32_srandom_r(42, 54)): the first outputs of the reference code.
  Pcg32 rng(42, 54);
  for (std::uint32_t expected : {0xa15c02b7u, 0x7b47f409u, 0xba1d3330u, 0x83d2f293u, 0xbfa4784bu, 0xcbed606eu})
    EXPECT_EQ(rng.next(), expected);
  // from_seed mixes one value into seed and stream.
  Pcg32 a = Pcg32::from_seed(7), b(splitmix64(7), splitmix64(7 ^ 0x5851f42d4c957f2dULL));
  for (int i = 0; i < 4; ++i) EXPECT_EQ(a.next(), b.next());
  EXPECT_EQ(splitmix64(0), 0xe220a8397b1dcdafULL);  // SplitMix64's first output from state 0
}

TEST(Lights, GenerationIsDeterministicAndSeeded) {
  LightSetSpec spec{.count = 200, .seed = 42, .spot_fraction = 0.3f};
  const LightSet a = generate_lights(atrium1(), spec);
  const LightSet b = generate_lights(atrium1(), spec);
  ASSERT_EQ(a.lights.size(), 200u);
  ASSERT_EQ(b.lights.size(), 200u);
  for (std::size_t i = 0; i < a.lights.size(); ++i) EXPECT_TRUE(same_light(a.lights[i], b.lights[i])) << i;
  spec.seed = 43;
  const LightSet c = generate_lights(atrium1(), spec);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < c.lights.size(); ++i) differ += same_light(a.lights[i], c.lights[i]) ? 0 : 1;
  EXPECT_GT(differ, 190u);
}

TEST(Lights, EachLightDependsOnlyOnSeedAndIndex) {
  LightSetSpec spec;
  spec.count = 16;
  const LightSet small = generate_lights(atrium1(), spec);
  spec.count = 64;
  const LightSet big = generate_lights(atrium1(), spec);
  for (std::size_t i = 0; i < small.lights.size(); ++i) EXPECT_TRUE(same_light(small.lights[i], big.lights[i])) << i;
}

TEST(Lights, RadiiPositionsAndSpotsFollowTheSpec) {
  const Scene& s = atrium1();
  const LightSetSpec spec{
      .count = 400, .seed = 7, .min_radius_fraction = 0.01f, .max_radius_fraction = 0.05f, .spot_fraction = 0.25f};
  const LightSet set = generate_lights(s, spec);
  const float diag = glm::length(s.bounds.extent());
  std::size_t spots = 0;
  float min_r = 1e30f, max_r = 0.0f;
  for (const Light& l : set.lights) {
    EXPECT_GE(l.radius, diag * 0.01f * 0.9999f);
    EXPECT_LE(l.radius, diag * 0.05f * 1.0001f);
    min_r = std::min(min_r, l.radius);
    max_r = std::max(max_r, l.radius);
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(l.position[k], s.bounds.min[k]);
      EXPECT_LE(l.position[k], s.bounds.max[k]);
    }
    EXPECT_GT(l.intensity, 0.0f);
    EXPECT_GT(l.color.x + l.color.y + l.color.z, 0.5f);
    if (l.type == Light::Type::Spot) {
      ++spots;
      EXPECT_NEAR(glm::length(l.direction), 1.0f, 1e-5f);
      EXPECT_LT(l.direction.y, -0.85f);  // pointing down-ish
      EXPECT_GE(l.cos_inner, l.cos_outer);
      EXPECT_GT(l.cos_outer, 0.7f);
    }
  }
  EXPECT_EQ(spots, 100u);  // exactly floor(400 * 0.25)
  EXPECT_LT(min_r, diag * 0.015f);  // the range is actually spread
  EXPECT_GT(max_r, diag * 0.045f);
}

TEST(Lights, NearSurfacesSitCloseToTheGeometry) {
  // On a single quad (the floor, y=0, 10 x 10 m) lights are lifted off it by 10%..50% of their radius.
  Scene s;
  SubMesh quad;
  quad.positions = {{0, 0, 0}, {10, 0, 0}, {10, 0, -10}, {0, 0, -10}};
  quad.normals.assign(4, {0, 1, 0});
  quad.uvs.assign(4, {0, 0});
  quad.indices = {0, 1, 2, 0, 2, 3};
  s.submeshes.push_back(quad);
  s.materials.push_back(Material{});
  s.instances.push_back(Instance{});
  s.bounds = {{0, 0, -10}, {10, 5, 0}};  // room above the floor
  LightSetSpec spec;
  spec.count = 100;
  const LightSet set = generate_lights(s, spec);
  for (const Light& l : set.lights) {
    EXPECT_GE(l.position.y, 0.1f * l.radius * 0.999f);
    EXPECT_LE(l.position.y, 0.5f * l.radius * 1.001f);
  }
  spec.near_surfaces = false;
  const LightSet uniform = generate_lights(s, spec);
  float max_y = 0.0f;
  for (const Light& l : uniform.lights) max_y = std::max(max_y, l.position.y);
  EXPECT_GT(max_y, 2.5f);  // spread through the whole volume
}

TEST(Lights, AttenuationIsExactlyZeroAtAndBeyondTheRadius) {
  for (float r : {0.1f, 1.0f, 3.7f, 250.0f}) {
    EXPECT_EQ(light_attenuation(r, r), 0.0f);
    EXPECT_EQ(light_attenuation(std::nextafter(r, 1e30f), r), 0.0f);
    EXPECT_EQ(light_attenuation(r * 2.0f, r), 0.0f);
    EXPECT_GT(light_attenuation(std::nextafter(r, 0.0f), r), -1e-30f);
    EXPECT_EQ(light_attenuation(0.0f, r), 1.0f);
    float prev = 1.0f;
    for (int i = 1; i <= 100; ++i) {
      const float a = light_attenuation(r * static_cast<float>(i) / 100.0f, r);
      EXPECT_LE(a, prev);
      prev = a;
    }
  }
}

// A light file line as docs/lights.md writes it: every float with 9 significant digits (%.9g).
std::string light_line(const Light& l) {
  std::string line = l.type == Light::Type::Spot ? "spot" : "point";
  auto add = [&line](float f) {
    char buf[32];
    std::snprintf(buf, sizeof buf, " %.9g", static_cast<double>(f));
    line += buf;
  };
  for (float f : {l.position.x, l.position.y, l.position.z, l.radius, l.color.x, l.color.y, l.color.z, l.intensity})
    add(f);
  if (l.type == Light::Type::Spot)
    for (float f : {l.direction.x, l.direction.y, l.direction.z, l.cos_inner, l.cos_outer}) add(f);
  return line + "\n";
}

TEST(Lights, NineDigitFloatsReadBackBitIdentical) {
  const LightSetSpec spec{.count = 300, .seed = 99, .spot_fraction = 0.5f};
  const LightSet set = generate_lights(atrium1(), spec);
  const std::string p = temp_path("nine_digits.lights");
  {
    std::ofstream out(p, std::ios::trunc);
    out << "tbdrsim-lights 1\n";
    for (const Light& l : set.lights) out << light_line(l);
  }
  const LightSet back = read_light_file(p);
  ASSERT_EQ(back.lights.size(), set.lights.size());
  for (std::size_t i = 0; i < set.lights.size(); ++i) EXPECT_TRUE(same_light(set.lights[i], back.lights[i])) << i;
}

TEST(Lights, HandWrittenFileWithCommentsReads) {
  const std::string p = temp_path("hand.lights");
  std::ofstream(p) << "# my lights\n\n  tbdrsim-lights 1   # version\n"
                      "\tpoint 1 2 3 4.5 1 1 1 2   # a warm one\n"
                      "spot 0 5 0 3 1 0.5 0.25 1 0 -1 0 0.95 0.8\n#end\n";
  const LightSet set = read_light_file(p);
  ASSERT_EQ(set.lights.size(), 2u);
  EXPECT_EQ(set.lights[0].type, Light::Type::Point);
  EXPECT_FLOAT_EQ(set.lights[0].radius, 4.5f);
  EXPECT_FLOAT_EQ(set.lights[0].intensity, 2.0f);
  EXPECT_EQ(set.lights[1].type, Light::Type::Spot);
  EXPECT_FLOAT_EQ(set.lights[1].cos_outer, 0.8f);
  EXPECT_EQ(set.lights[1].direction, glm::vec3(0, -1, 0));
}

TEST(Lights, TheDocumentedExampleReads) {
  const std::string p = temp_path("doc_example.lights");
  std::ofstream(p) << "tbdrsim-lights 1\n# 3 lights\n# point x y z radius r g b intensity\n"
                      "# spot  x y z radius r g b intensity dx dy dz cos_inner cos_outer\n"
                      "point 1.5 2 -3.25 0.75 1 0.850000024 0.649999976 1.5\n"
                      "point 0 4 0 2 0.349999994 0.550000012 1 0.5\n"
                      "spot 3 6 1 4.5 1 0.949999988 0.850000024 2 0.196116135 -0.980580688 0 0.949999988 "
                      "0.800000012\n";
  const LightSet set = read_light_file(p);
  ASSERT_EQ(set.lights.size(), 3u);
  EXPECT_EQ(set.lights[0].color, glm::vec3(1.0f, 0.85f, 0.65f));
  EXPECT_EQ(set.lights[1].color, glm::vec3(0.35f, 0.55f, 1.0f));
  EXPECT_EQ(set.lights[2].type, Light::Type::Spot);
  EXPECT_EQ(set.lights[2].cos_inner, 0.95f);
  EXPECT_EQ(set.lights[2].cos_outer, 0.8f);
  // The example's lines are these lights written with 9 significant digits.
  std::string lines;
  for (const Light& l : set.lights) lines += light_line(l);
  const std::string text = slurp(p);
  EXPECT_EQ(text.substr(text.size() - lines.size()), lines);
}

std::string read_error(const std::string& text) {
  const std::string p = temp_path("bad.lights");
  std::ofstream(p, std::ios::trunc) << text;
  try {
    read_light_file(p);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Lights, MalformedLinesNameFileLineAndToken) {
  const std::string p = temp_path("bad.lights");
  const std::string head = "tbdrsim-lights 1\npoint 0 0 0 1 1 1 1 1\n";
  std::string e = read_error(head + "# fine\npoint 0 0 zero 1 1 1 1 1\n");
  EXPECT_NE(e.find(p + ":4: expected a finite number for z, got 'zero'"), std::string::npos) << e;
  e = read_error(head + "lamp 0 0 0 1 1 1 1 1\n");
  EXPECT_NE(e.find(p + ":3: unknown light type 'lamp'"), std::string::npos) << e;
  e = read_error(head + "point 0 0 0 1 1 1 1\n");
  EXPECT_NE(e.find(p + ":3: point light needs 8 numbers, got 7"), std::string::npos) << e;
  e = read_error(head + "point 0 0 0 1 1 1 1 1 9\n");
  EXPECT_NE(e.find(":3:"), std::string::npos) << e;
  EXPECT_NE(e.find("extra token '9'"), std::string::npos) << e;
  e = read_error(head + "point 0 0 0 -1 1 1 1 1\n");
  EXPECT_NE(e.find(p + ":3: radius must be > 0, got '-1'"), std::string::npos) << e;
  e = read_error(head + "point 0 0 0 nan 1 1 1 1\n");
  EXPECT_NE(e.find(":3: expected a finite number for radius, got 'nan'"), std::string::npos) << e;
  e = read_error(head + "spot 0 0 0 1 1 1 1 1 0 -2 0 0.9 0.8\n");
  EXPECT_NE(e.find(":3: spot direction must be a unit vector"), std::string::npos) << e;
  e = read_error(head + "spot 0 0 0 1 1 1 1 1 0 -1 0 0.7 0.8\n");
  EXPECT_NE(e.find(":3: spot cones need"), std::string::npos) << e;
  e = read_error("tbdrsim-lights 2\n");
  EXPECT_NE(e.find(p + ":1: unsupported light file version '2'"), std::string::npos) << e;
  e = read_error("point 0 0 0 1 1 1 1 1\n");
  EXPECT_NE(e.find(p + ":1: expected the header"), std::string::npos) << e;
  e = read_error("");
  EXPECT_NE(e.find("missing the header"), std::string::npos) << e;
  EXPECT_THROW(read_light_file(temp_path("does_not_exist.lights")), InputError);
}

TEST(Lights, InvalidSpecsAreRejected) {
  LightSetSpec spec;
  spec.min_radius_fraction = 0.1f;
  spec.max_radius_fraction = 0.05f;
  EXPECT_THROW(generate_lights(atrium1(), spec), InputError);
  spec = LightSetSpec{};
  spec.spot_fraction = 1.5f;
  EXPECT_THROW(generate_lights(atrium1(), spec), InputError);
}

}  // namespace
}  // namespace tbdr
