// Hostile input (issue 16): every input the reader accepted but should refuse is refused with
// file:line (or the field), the offending token and what was expected, before any work; every
// declared limit (docs/limits.md) is enforced; a UTF-8 byte-order mark is accepted.
#include <gtest/gtest.h>

#include <unistd.h>

#include <climits>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "app/sweep_spec.hpp"
#include "kernel/errors.hpp"
#include "kernel/params.hpp"
#include "models/hw_config.hpp"
#include "scene/atrium.hpp"
#include "scene/gltf_loader.hpp"
#include "input_validation_fixture.hpp"
#include "trace/trace.hpp"

namespace tbdr {
namespace {

using namespace input_validation;
const testing_scratch::ScratchCleanup cleanup{"input_validation"};

// ---- the trace: references and numeric ranges ---------------------------------------------------

TEST(InputValidation, BaseTraceIsAccepted) {
  // The refusals below differ from this accepted trace by one line each.
  const Trace t = parse(trace_text(kCamera, "", kPass));
  EXPECT_EQ(t.commands.size(), 1u);
}

TEST(InputValidation, DrawOfASubMeshOrMaterialTheSceneLacksIsRefusedBeforeWork) {
  const std::string& body_sub = kDrawOfAMissingSubMesh;
  const Trace t = parse(trace_text(kCamera, "", body_sub));
  const Scene atrium = make_atrium(1);
  try {
    check_scene_references(t, atrium, "t.trace");
    ADD_FAILURE() << "a draw of a missing sub-mesh was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "t.trace:10");
    EXPECT_NE(std::string(e.what()).find("submesh='no_such_mesh'"), std::string::npos) << e.what();
  }
  std::string body_mat = body_sub;
  body_mat.replace(body_mat.find("submesh=no_such_mesh"), 20, "material=no_such_mat");
  EXPECT_THROW(check_scene_references(parse(trace_text(kCamera, "", body_mat)), atrium, "t.trace"), InputError);
  // A name the atrium has passes.
  body_mat.replace(body_mat.find("material=no_such_mat"), 20, "material=\"" + atrium.materials.front().name + "\"");
  EXPECT_NO_THROW(check_scene_references(parse(trace_text(kCamera, "", body_mat)), atrium, "t.trace"));
  // Through the command line: tests/test_input_validation_cli.cpp.
}

// The camera line (line 4 of trace_text's trace) `camera ARGS` is refused, naming every `tokens`.
void expect_camera_refused(const std::string& args, std::initializer_list<std::string> tokens) {
  expect_refused(trace_text("camera " + args, "", kPass), 4, tokens);
}

TEST(InputValidation, CameraUpParallelToTheViewIsRefused) {
  expect_camera_refused("eye=0,0,0 target=0,5,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100", {"up '0,1,0'", "parallel"});
  // Anti-parallel too, and 0.01 degrees off (sine 1.7e-4 < 1e-3).
  expect_camera_refused("eye=0,0,0 target=0,5,0 up=0,-1,0 fov_y_deg=60 near=0.1 far=100", {"parallel"});
  expect_camera_refused("eye=0,0,0 target=0,5,0 up=0.00017,1,0 fov_y_deg=60 near=0.1 far=100", {"parallel"});
  // 0.1 degrees off (sine 1.7e-3) is a usable basis.
  EXPECT_NO_THROW(parse(trace_text("camera eye=0,0,0 target=0,5,0 up=0.0017,1,0 fov_y_deg=60 near=0.1 far=100", "", kPass)));
}

TEST(InputValidation, DegenerateProjectionsAreRefused) {
  expect_camera_refused("eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=1e-30 near=0.1 far=100",
                        {"fov_y_deg '1e-30'", "[0.01, 179]"});
  expect_camera_refused("eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=179.5 near=0.1 far=100", {"fov_y_deg '179.5'"});
  expect_camera_refused("eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=60 near=1e-30 far=1e38", {"near '1e-30'"});
  expect_camera_refused("eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=60 near=0.1 far=1e38", {"far '1e38'"});
  // far/near = 1e8 > 2^24 = 1.68e7, each within its own range.
  expect_camera_refused("eye=0,2,10 target=0,2,0 up=0,1,0 fov_y_deg=60 near=1e-3 far=1e5", {"far/near", "16777216"});
  expect_camera_refused("eye=0,2,1e20 target=0,2,0 up=0,1,0 fov_y_deg=60 near=0.1 far=100", {"eye=0,2,1e20"});
}

TEST(InputValidation, LightBufferSmallerThanTheLightsIsRefused) {
  // 104 lights need 104 x 48 = 4992 bytes; 192 holds 4.
  std::string lights;
  for (int i = 0; i < 104; ++i) lights += "light point position=0,1,0 radius=1 color=1,1,1 intensity=1\n";
  const std::string decl = lights + "buffer lights bytes=192 traffic=light_data content=lights upload=yes\n";  // line 109
  expect_refused(trace_text(kCamera, decl, kPass), 109, {"bytes=192", "104 lights need 4992"});
  std::string ok = decl;
  ok.replace(ok.find("bytes=192"), 9, "bytes=4992");
  EXPECT_NO_THROW(parse(trace_text(kCamera, ok, kPass)));
}

TEST(InputValidation, DispatchSizesBeyondVulkanLimitsAreRefused) {
  const std::string decl = "buffer out bytes=64 traffic=other content=other\n";
  expect_refused(trace_text(kCamera, decl,
                            "dispatch tile_light_cull groups=4294967295,4294967295,4294967295 group_size=16,16,1 writes=out\n"),
                 8, {"groups=4294967295,4294967295,4294967295", "65535"});
  expect_refused(trace_text(kCamera, decl, "dispatch tile_light_cull groups=1,1,1 group_size=64,64,1 writes=out\n"), 8,
                 {"group_size=64,64,1", "4096 invocations", "1024"});
}

TEST(InputValidation, DispatchOfMoreWorkgroupsThanTheFrameCanUseIsRefused) {
  // The 64x64 frame has 4,096 pixels: at most 256 workgroups per pixel, 1,048,576. The issue's
  // 65535^3 (2.8e14) is refused at its line; 1024 x 1024 x 1 is the limit itself and is read.
  const std::string decl = "buffer out bytes=64 traffic=other content=other\n";
  expect_refused(trace_text(kCamera, decl, "dispatch tile_light_cull groups=65535,65535,65535 group_size=32,32,1 writes=out\n"),
                 8, {"281462092005375 workgroups", "64x64 frame", "at most 256 per pixel (1048576)"});
  expect_refused(trace_text(kCamera, decl, "dispatch tile_light_cull groups=1024,1024,2 group_size=16,16,1 writes=out\n"),
                 8, {"2097152 workgroups"});
  EXPECT_NO_THROW(parse(trace_text(kCamera, decl, "dispatch tile_light_cull groups=1024,1024,1 group_size=16,16,1 writes=out\n")));
}

TEST(InputValidation, AtriumDetailOutsideOneToFiveIsRefused) {
  std::string t = trace_text(kCamera, "", kPass);
  for (const char* bad : {"detail=0", "detail=6", "detail=16"}) {
    std::string text = t;
    text.replace(text.find("detail=1"), 8, bad);
    expect_refused(text, 2, {"detail"});
  }
}

// ---- the trace: declared limits ------------------------------------------------------------------

TEST(InputValidation, HugeBufferIsRefusedNotAllocated) {
  // 1 TiB (2^40) > kMaxBufferBytes = 16 GiB; an upload buffer above 256 MiB is refused too.
  expect_refused(trace_text(kCamera, "buffer big bytes=1099511627776 traffic=other content=other upload=yes\n", kPass), 5,
                 {"1099511627776", "0..17179869184"});
  expect_refused(trace_text(kCamera, "buffer big bytes=268435457 traffic=other content=other upload=yes\n", kPass), 5,
                 {"upload=yes", "268435456"});
  EXPECT_NO_THROW(parse(trace_text(kCamera, "buffer big bytes=17179869184 traffic=other content=other\n", kPass)));
}

TEST(InputValidation, FrameLargerThanTheSampleBudgetIsRefused) {
  std::string t = trace_text(kCamera, "", kPass);
  // 16384 x 16384 x 2 = 2^29 samples > 2^28; at one sample it is exactly the budget.
  std::string two = t;
  two.replace(two.find("frame width=64 height=64 samples=1"), 34, "frame width=16384 height=16384 samples=2");
  expect_refused(two, 3, {"536870912 samples", "268435456"});
  std::string side = t;
  side.replace(side.find("width=64"), 8, "width=16385");
  expect_refused(side, 3, {"16385", "0..16384"});
}

TEST(InputValidation, MoreCommandsThanTheLimitAreRefusedAsTheyAreRead) {
  // 65,537 barriers: one past kMaxTraceCommands; the error names the first line beyond it.
  std::string body;
  for (std::uint64_t i = 0; i <= kMaxTraceCommands; ++i) body += "barrier resources=all\n";
  expect_refused(trace_text(kCamera, "", body), 7 + static_cast<int>(kMaxTraceCommands), {"65536 passes, dispatches and barriers"});
}

TEST(InputValidation, TraceFileLargerThanTheLimitIsRefusedBeforeReading) {
  const fs::path dir = dir_for("big_trace");
  const fs::path p = dir / "big.trace";
  write_file(p, trace_text(kCamera, "", kPass));
  fs::resize_file(p, kMaxTraceBytes + 1);  // sparse: no disk, and refused by its size alone
  try {
    read_trace(p.string());
    ADD_FAILURE() << "a trace of kMaxTraceBytes + 1 was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("268435457 bytes"), std::string::npos) << e.what();
  }
}

TEST(InputValidation, PathsLongerThanTheFileSystemAllowsAreInputErrors) {
  const long name_max = ::pathconf(fs::temp_directory_path().c_str(), _PC_NAME_MAX);
  ASSERT_GT(name_max, 0);
  const std::string long_name = (fs::temp_directory_path() / std::string(static_cast<std::size_t>(name_max) + 1, 'a')).string() + ".trace";
  EXPECT_THROW(read_trace(long_name), InputError);
  std::string long_path = fs::temp_directory_path().string();
  while (long_path.size() < PATH_MAX + 10) long_path += "/abc";
  EXPECT_THROW(read_trace(long_path), InputError);
}

// ---- byte-order marks ----------------------------------------------------------------------------

const std::string kBom = "\xEF\xBB\xBF";

TEST(InputValidation, Utf8ByteOrderMarkIsAcceptedInTraceConfigAndSweepFiles) {
  const Trace t = parse(kBom + trace_text(kCamera, "", kPass));
  EXPECT_EQ(t.version, 2);

  const fs::path dir = dir_for("bom");
  write_file(dir / "c.ini", kBom + "[isp]\ntag_buffers = 4\n");
  const ParamTable& table = hw_params().table();
  const ResolvedParams p = table.resolve({(dir / "c.ini").string()}, {});
  EXPECT_EQ(format_param_value(p.values[static_cast<std::size_t>(table.find("isp.tag_buffers"))]), "4");

  write_file(dir / "t.trace", "x");
  write_file(dir / "s.ini", kBom + "[sweep]\ntrace = t.trace\n[vary]\nisp.tag_buffers = 1, 2\n");
  const SweepSpec s = parse_sweep_file((dir / "s.ini").string());
  EXPECT_EQ(expand_sweep(s).size(), 2u);
}

// ---- sweeps --------------------------------------------------------------------------------------

/// The first real-valued hardware parameter whose range holds 1.
std::string a_real_parameter() {
  for (const auto& d : hw_params().table().decls())
    if (d.type == ParamType::Real && d.min <= 1.0 && d.max >= 1.0) return d.key;
  return {};
}

TEST(InputValidation, SweepValueWrittenTwiceInTwoSpellingsIsRefused) {
  const std::string key = a_real_parameter();
  ASSERT_FALSE(key.empty());
  const fs::path dir = dir_for("sweep_twice");
  write_file(dir / "t.trace", "x");
  write_file(dir / "s.ini", "[sweep]\ntrace = t.trace\n[vary]\n" + key + " = 1.0, 1\n");  // line 4
  try {
    parse_sweep_file((dir / "s.ini").string());
    ADD_FAILURE() << "'1.0, 1' accepted for " << key;
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "s.ini").string() + ":4");
    EXPECT_NE(std::string(e.what()).find("'1' and '1.0' are the same value"), std::string::npos) << e.what();
  }
}

TEST(InputValidation, SweepOfMoreThanAMillionPointsIsRefusedBeforeExpanding) {
  // Integer parameters whose range holds 1..1000.
  std::vector<std::string> keys;
  for (const auto& d : hw_params().table().decls())
    if (d.type == ParamType::Int && d.min <= 1 && d.max >= 1000) keys.push_back(d.key);
  ASSERT_GE(keys.size(), 2u);
  const fs::path dir = dir_for("sweep_big");
  write_file(dir / "t.trace", "x");
  // 1000 repetitions x 1000 x 1000 values = 10^9 points (std::bad_alloc before): refused at the file.
  write_file(dir / "s.ini", "[sweep]\ntrace = t.trace\nrepetitions = 1000\n[vary]\n" + keys[0] + " = 1..1000\n" + keys[1] +
                                " = 1..1000\n");
  try {
    parse_sweep_file((dir / "s.ini").string());
    ADD_FAILURE() << "10^9 points accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "s.ini").string());
    EXPECT_NE(std::string(e.what()).find("more than 1000000 points"), std::string::npos) << e.what();
  }
  // 1 x 1000 x 1000 = 10^6 points is exactly the limit: accepted (expanding is left to a sweep).
  write_file(dir / "s.ini", "[sweep]\ntrace = t.trace\n[vary]\n" + keys[0] + " = 1..1000\n" + keys[1] + " = 1..1000\n");
  EXPECT_NO_THROW(parse_sweep_file((dir / "s.ini").string()));
}

// ---- glTF ----------------------------------------------------------------------------------------

// A one-triangle glTF with its buffer in a data URI; `patch` edits its JSON text.
std::string tiny_gltf(const std::string& extra_top = "", const std::string& primitive_extra = "",
                      const std::string& attributes = "\"POSITION\": 0") {
  // 3 x VEC3 float positions (0,0,0) (1,0,0) (0,1,0), base64 of 36 bytes.
  const std::string positions = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
  return "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}], \"nodes\": [{\"mesh\": 0}],"
         "\"meshes\": [{\"primitives\": [{\"attributes\": {" + attributes + "}" + primitive_extra + "}]}],"
         "\"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\","
         "\"max\": [1, 1, 0], \"min\": [0, 0, 0]}],"
         "\"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}],"
         "\"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/octet-stream;base64," + positions + "\"}]" +
         extra_top + "}";
}

// Loading `json` throws an InputError naming the file and containing `field`.
void expect_gltf_refused(const std::string& json, const std::string& field) {
  const fs::path dir = dir_for("gltf");
  const fs::path p = dir / "x.gltf";
  write_file(p, json);
  try {
    load_gltf(p.string());
    ADD_FAILURE() << "accepted: " << json;
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), p.string()) << e.what();
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << "'" << field << "' not in " << e.what();
  }
}

TEST(InputValidation, GltfBaseFileLoads) {
  const fs::path p = dir_for("gltf_ok") / "ok.gltf";
  write_file(p, tiny_gltf());
  EXPECT_EQ(load_gltf(p.string()).triangle_count(), 1u);
}

TEST(InputValidation, GltfWrongJsonTypesAreRefusedNamingTheField) {
  std::string s = tiny_gltf();
  auto with = [](std::string text, const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  expect_gltf_refused(with(s, "\"scene\": 0", "\"scene\": \"hello\""), "field 'scene': expected a non-negative integer");
  expect_gltf_refused(with(s, "\"count\": 3", "\"count\": \"3\""), "field 'accessors[0].count'");
  expect_gltf_refused(with(s, "\"count\": 3", "\"count\": 3.5"), "field 'accessors[0].count'");
  expect_gltf_refused(with(s, "\"nodes\": [0]", "\"nodes\": [-1]"), "field 'scenes[0].nodes[0]'");
  expect_gltf_refused(with(s, "\"max\": [1, 1, 0]", "\"max\": [1, \"a\", 0]"), "field 'accessors[0].max[1]'");
  expect_gltf_refused(with(s, "{\"mesh\": 0}", "{\"mesh\": 0, \"name\": 42}"), "field 'nodes[0].name': expected a string");
  expect_gltf_refused(with(s, "\"asset\": {\"version\": \"2.0\"}", "\"asset\": {\"version\": 2}"), "field 'asset.version'");
  expect_gltf_refused(with(s, "\"asset\": {\"version\": \"2.0\"}, ", ""), "field 'asset': required");
  expect_gltf_refused(tiny_gltf("", "", "\"POSITION\": \"zero\""), "field 'meshes[0].primitives[0].attributes.POSITION'");
  expect_gltf_refused(tiny_gltf(", \"materials\": [{\"pbrMetallicRoughness\": 5}]"),
                      "field 'materials[0].pbrMetallicRoughness': expected an object");
  expect_gltf_refused(tiny_gltf(", \"materials\": [{\"normalTexture\": {\"index\": 0, \"scale\": \"big\"}}]"),
                      "field 'materials[0].normalTexture.scale': expected a number");
  expect_gltf_refused(tiny_gltf(", \"materials\": [{\"extensions\": {\"KHR_x\": \"Not an object\"}}]"),
                      "field 'materials[0].extensions.KHR_x'");
}

TEST(InputValidation, GltfTexturedMaterialOnAPrimitiveWithoutItsTexcoordSetIsRefused) {
  // A 1x1 RGBA PNG, base64.
  const std::string png = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==";
  const std::string textured = ", \"materials\": [{\"pbrMetallicRoughness\": {\"baseColorTexture\": {\"index\": 0}}}],"
                               " \"textures\": [{\"source\": 0}], \"images\": [{\"uri\": \"data:image/png;base64," + png + "\"}]";
  // The same accessor as TEXCOORD_1 (VEC3 is the wrong type for uvs, but the set is missing first).
  expect_gltf_refused(tiny_gltf(textured, ", \"material\": 0", "\"POSITION\": 0, \"TEXCOORD_1\": 0"), "TEXCOORD_0");
}

TEST(InputValidation, AssimpBrokenGltfCorpusIsRefused) {
  if (!fs::is_directory(kAssimpGltf2 / "wrongTypes")) GTEST_SKIP() << "assimp-testmodels not installed (apt install assimp-testmodels)";
  for (const auto& [file, field] : kAssimpBrokenGltf) {
    const std::string p = (kAssimpGltf2 / file).string();
    try {
      load_gltf(p);
      ADD_FAILURE() << p << " loaded";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), p) << e.what();
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << "'" << field << "' not in " << e.what();
    }
  }
}

}  // namespace
}  // namespace tbdr
